"""Flow compatibility: re-exports.

Flow < 0.5 package ``flow.envs.loop`` (the ring envs live in ``flowrun.envs.ring``).
"""

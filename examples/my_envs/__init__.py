"""An example package holding a custom flowrun environment.

See the README section "Write your own environment".

Load it from a config with ``env: {class: "my_envs.envs:MyEnv"}``; flowrun finds the package
next to the config file (``examples/custom_env.yaml``), on ``PYTHONPATH`` or installed.
"""

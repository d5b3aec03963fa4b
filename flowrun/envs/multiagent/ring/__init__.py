"""Flow compatibility: re-exports.

Flow's ``flow.envs.multiagent.ring`` import path
(flowrun's classes; importing it imports PettingZoo).
"""

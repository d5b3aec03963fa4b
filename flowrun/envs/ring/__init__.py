"""Ring-road environments (Flow's ``flow.envs.ring``)."""

"""Flow compatibility: re-exports. Flow's ``flow.core.rewards`` path.

The functions (Flow's reward functions that take the env) live in
:mod:`flowrun.envs.flow_rewards`, whose ``__all__`` is the one list of their names; the pure
formulas behind them in :mod:`flowrun.envs.rewards`.
"""

from flowrun.envs.flow_rewards import *  # noqa: F403
from flowrun.envs.flow_rewards import __all__ as __all__

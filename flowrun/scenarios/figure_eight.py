"""Flow compatibility: re-exports.

Flow < 0.5 module path ``flow.scenarios.figure_eight`` (now ``flowrun.networks``).
"""

from flowrun.networks.figure_eight import (
    ADDITIONAL_NET_PARAMS,
    Figure8Scenario,
    FigureEightScenario,
)

__all__ = ["ADDITIONAL_NET_PARAMS", "Figure8Scenario", "FigureEightScenario"]

"""Rules every placement shares: how many lanes ``lanes_distribution`` spreads cars over, and
the error when the cars do not fit."""

from __future__ import annotations

import logging

from flowrun.errors import ConfigError

log = logging.getLogger(__name__)


def lanes_spread(lanes_distribution: float) -> float:
    """``lanes_distribution`` with values below 1 counted as 1, as Flow does (with a warning).

    Args:
        lanes_distribution: ``InitialConfig.lanes_distribution`` (``inf`` = all lanes).
    """
    if lanes_distribution < 1:
        log.warning('"lanes_distribution" is too small (%s); setting to 1', lanes_distribution)
        return 1.0
    return float(lanes_distribution)


def no_room(n: int, unit: float, room: float, bunching: float) -> ConfigError:
    """The error of ``n`` cars needing ``unit`` m each where a lane offers ``room`` m."""
    return ConfigError(
        f"{n} vehicles need {unit:.1f} m each (length + minGap + min_gap) but the edges offer "
        f"{room:.1f} m per lane after bunching {bunching} m; use fewer vehicles, more edges "
        "(edges_distribution), more lanes or less bunching",
        path="edges_distribution",
    )

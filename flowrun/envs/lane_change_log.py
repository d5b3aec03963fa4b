"""Envs whose ``get_last_lc`` reads count lane changes from the start of each episode."""

from __future__ import annotations

from typing import Any


class LogsLaneChanges:
    """Mixin for an :class:`~flowrun.envs.base.Env`: each ``reset`` (after the warm-up) starts
    the kernel's lane-change log, so Flow's ``get_last_lc`` counts from there."""

    k: Any

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new episode; lane changes are logged from here on (``get_last_lc``)."""
        obs, info = super().reset(seed=seed, options=options)  # type: ignore[misc]
        self.k.vehicle.lane_change_log()
        return obs, info

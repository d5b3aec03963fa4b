"""Clipping an agent's action to its action space (Flow's ``clip_actions``)."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np


class ActionClipper:
    """Clips actions to a ``Box`` space, or each ``Box`` part of a ``Tuple`` space.

    The bounds are read once, on the first call (Flow's spaces are properties that may be
    costly to build). Other spaces, and every space when ``enabled`` is false, pass actions
    through unchanged.

    Args:
        enabled: Flow's ``EnvParams.clip_actions``.
    """

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None
        self._tuple: gymnasium.spaces.Tuple | None = None
        self._ready = False

    def clip(self, space: gymnasium.Space[Any], action: Any) -> Any:
        """``action`` clipped to ``space`` (a float array for a Box; a tuple for a Tuple)."""
        if not self._ready:
            self._ready = True
            if self.enabled and isinstance(space, gymnasium.spaces.Tuple):
                self._tuple = space
            elif self.enabled and isinstance(space, gymnasium.spaces.Box):
                self._bounds = (
                    np.asarray(space.low, np.float64),
                    np.asarray(space.high, np.float64),
                )
        if self._tuple is not None:
            return tuple(
                np.clip(np.asarray(a, dtype=np.float64), sub.low, sub.high)
                if isinstance(sub, gymnasium.spaces.Box)
                else a
                for a, sub in zip(action, self._tuple.spaces, strict=True)
            )
        if self._bounds is None:
            return action
        low, high = self._bounds
        return np.minimum(np.maximum(np.asarray(action, dtype=np.float64), low), high)

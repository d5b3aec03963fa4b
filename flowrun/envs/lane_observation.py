"""What an RL car sees of its neighbours on every lane: the lane-changing envs' observation."""

from __future__ import annotations

from typing import Any

import numpy as np

from flowrun.types import FloatArray


def lane_neighbours(vk: Any, veh_id: str, lanes: int, gap_scale: float, v_max: float) -> FloatArray:
    """Car ``veh_id``'s nearest neighbours on each of the first ``lanes`` lanes of its edge.

    Returns a ``(4, lanes)`` array: the gaps to the nearest car ahead and behind, in m /
    ``gap_scale`` (1 on lanes the edge does not have), and those cars' speeds in m/s /
    ``v_max`` (0 there); the vehicle kernel's ``get_lane_headways``, ``get_lane_tailways``,
    ``get_lane_leaders_speed`` and ``get_lane_followers_speed``.
    """
    near = np.zeros((4, lanes))
    near[:2] = 1.0  # no car ahead / behind: the largest gap
    ahead, behind = vk.get_lane_headways(veh_id), vk.get_lane_tailways(veh_id)
    m = min(len(ahead), lanes)
    near[0, :m] = np.asarray(ahead[:m]) / gap_scale
    near[1, :m] = np.asarray(behind[:m]) / gap_scale
    near[2, :m] = np.asarray(vk.get_lane_leaders_speed(veh_id)[:m]) / v_max
    near[3, :m] = np.asarray(vk.get_lane_followers_speed(veh_id)[:m]) / v_max
    return near

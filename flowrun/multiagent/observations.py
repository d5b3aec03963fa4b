"""Per-AV observations Flow's multi-agent envs share, read from the kernel's getters."""

from __future__ import annotations

from typing import Any

import numpy as np

from flowrun.envs.ring.tasks import partial_observation
from flowrun.types import FloatArray

#: Bounds of the neighbour 5-vector (speed, relative leader speed, headway, relative follower
#: speed, tailway, normalised): Flow's declared ``[-5, 5]`` (``MultiAgentMergePOEnv``)
NEIGHBOUR_LOW = np.full(5, -5.0, dtype=np.float32)
NEIGHBOUR_HIGH = np.full(5, 5.0, dtype=np.float32)


def neighbour_obs(vk: Any, veh_id: str, max_speed: float, max_length: float) -> FloatArray:
    """Flow's 5 values of an AV and its two neighbours (``MultiAgentMergePOEnv``).

    ``[v / V, (v_lead - v) / V, headway / L, (v - v_follow) / V, tailway / L]`` with ``V``
    the network's max speed (m/s) and ``L`` its length (m). Without a leader
    ``v_lead = V`` and ``headway = L``; without a follower ``v_follow = 0`` and
    ``tailway = L``. Gaps are bumper to bumper: the AV's headway (the kernel's, which also
    holds across junctions, where Flow's ``x_lead - x - length`` does not) and, as Flow, the
    follower's headway as the tailway.

    Args:
        vk: the vehicle kernel (``env.k.vehicle``).
        veh_id: the AV.
        max_speed: normaliser of speeds, m/s.
        max_length: normaliser of gaps, m.
    """
    speed = float(vk.get_speed(veh_id))
    lead, follow = vk.get_leader(veh_id), vk.get_follower(veh_id)
    if lead:
        lead_speed, headway = float(vk.get_speed(lead)), float(vk.get_headway(veh_id))
    else:
        lead_speed, headway = max_speed, max_length
    if follow:
        follow_speed, tailway = float(vk.get_speed(follow)), float(vk.get_headway(follow))
    else:
        follow_speed, tailway = 0.0, max_length
    return np.array(
        [
            speed / max_speed,
            (lead_speed - speed) / max_speed,
            headway / max_length,
            (speed - follow_speed) / max_speed,
            tailway / max_length,
        ]
    )


def leader_obs(vk: Any, agents: list[str], max_length: float) -> dict[str, FloatArray]:
    """Each AV's view in Flow's multi-agent ring envs: the single-agent ring's
    :func:`~flowrun.envs.ring.tasks.partial_observation` ``[v / 15, (v_lead - v) / 15,
    headway / max_length]`` with the bumper-to-bumper headway (``get_headway``) as the gap;
    a car alone on its ring is its own leader, with ``headway = max_length``.

    Args:
        vk: the vehicle kernel (``env.k.vehicle``).
        agents: the AVs.
        max_length: normaliser of the headway (the largest ring length), m.
    """
    obs = {}
    for rl_id in agents:
        lead = vk.get_leader(rl_id) or rl_id
        headway = float(vk.get_headway(rl_id)) if lead != rl_id else max_length
        obs[rl_id] = partial_observation(
            float(vk.get_speed(rl_id)), float(vk.get_speed(lead)), headway, max_length
        )
    return obs

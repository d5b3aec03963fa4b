"""RL signal control on Flow's traffic-light grid (Flow's ``flow.envs.traffic_light_grid``):
the partially observed env and the grid0/grid1 benchmark env.

Flow's module holds all four grid envs: the fully observed :class:`TrafficLightGridEnv` and
its test variant are re-exported from :mod:`flowrun.envs.traffic_light_grid_base`.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs import flow_rewards as rewards
from flowrun.envs import rewards as formulas
from flowrun.envs.signals import edge_number
from flowrun.envs.traffic_light_grid_base import (
    ADDITIONAL_ENV_PARAMS,
    GreenWaveTestEnv,
    TrafficLightGridEnv,
    TrafficLightGridTestEnv,
    reentry_edges,
)
from flowrun.errors import ConfigError
from flowrun.networks.base import Network

__all__ = [
    "ADDITIONAL_ENV_PARAMS",
    "ADDITIONAL_PO_ENV_PARAMS",
    "GreenWaveTestEnv",
    "PO_TrafficLightGridEnv",
    "TrafficLightGridBenchmarkEnv",
    "TrafficLightGridEnv",
    "TrafficLightGridPOEnv",
    "TrafficLightGridTestEnv",
    "reentry_edges",
]

ADDITIONAL_PO_ENV_PARAMS: dict[str, Any] = {
    # vehicles observed per incoming edge of each light
    "num_observed": 2,
    # desired speed of the benchmark's training reward, m/s
    "target_velocity": 30,
}
#: Flow's vehicle length in the edge density, m.
VEHICLE_LENGTH = 5.0
#: Flow's upper bound of every observed value.
OBS_HIGH = 3.0


class TrafficLightGridPOEnv(TrafficLightGridEnv):
    """Flow's ``TrafficLightGridPOEnv``: each light sees the cars nearest to it.

    Observation (``Box(0, 3)``, Flow's order): for each light (Flow's ``node_mapping``
    order) and each of its 4 incoming edges, the ``num_observed`` cars nearest the junction
    (zero-padded): their speeds / max speed, then distances to the junction / the longest
    edge, then Flow's edge numbers / (``num_edges`` - 1) — ``3 * 4 * num_observed * n``
    values; then per edge of the network ``5 m * cars / length`` and mean speed / max speed
    (``2 * edges``); then ``last_change``, ``direction``, ``currently_yellow``
    (``3 * n``). grid0 (3x3): 339 values; grid1 (5x5): 915.
    Reward: ``-delay - 0.2 * (cars standing still)``; ``-delay`` when ``evaluate``.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {
        **ADDITIONAL_ENV_PARAMS,
        **ADDITIONAL_PO_ENV_PARAMS,
    }

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        num = self.env_params.additional_params["num_observed"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise ConfigError(
                f"expected a whole number >= 1, got {num!r}",
                path="env.additional_params.num_observed",
            )
        self.num_observed = int(num)
        # there is one: check_network ran in the parent's __init__
        self.node_mapping: list[tuple[str, list[str]]] = list(
            getattr(self.network, "node_mapping", [])
        )
        self.edge_list = [e.id for e in self.network.spec.edges]
        self._edge_col = {e: i for i, e in enumerate(self.edge_list)}
        self._col_names: list[str] | None = None  # the lane table _col_by_index was built for
        self._col_by_index = np.zeros(0, dtype=np.int64)
        self._slot_by_index = np.zeros(0, dtype=np.int64)
        self._edge_len = np.array([e.length for e in self.network.spec.edges])
        norm = max(self.num_edges - 1, 1)
        self._edge_num = {e: edge_number(e, self.rows, self.cols) / norm for e in self.edge_list}
        self.observed_ids: list[str] = []
        # the observed edges in observation order (light by light), and for each network edge
        # its place in that order (-1: not observed)
        observed_edges = [edge for _, edges in self.node_mapping for edge in edges]
        self._slot_of_col = np.full(len(self.edge_list) + 1, -1, dtype=np.int64)  # +1: none
        for slot, edge in enumerate(observed_edges):
            self._slot_of_col[self._edge_col[edge]] = slot
        by_id = {e.id: e for e in self.network.spec.edges}
        self._slot_length = np.array([by_id[e].length for e in observed_edges])
        self._slot_num = np.array([self._edge_num[e] for e in observed_edges])

    @classmethod
    def check_network(cls, network: Network) -> None:
        """Lights (see the parent's), and a grid: each light's incoming edges.

        Raises:
            ConfigError: no light, or a network without ``node_mapping``.
        """
        super().check_network(network)
        if getattr(network, "node_mapping", None) is None:
            raise ConfigError(
                f"{cls.__name__} needs a grid network (its node_mapping of incoming edges "
                f"per light), not '{network.network_type or type(network).__name__}'; use "
                "network type traffic_light_grid",
                path="network.type",
            )

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """See the class docstring."""
        size = (3 * 4 * self.num_observed * self.num_traffic_lights + 2 * len(self.edge_list)
                + 3 * self.num_traffic_lights)  # fmt: skip
        return Box(low=0.0, high=OBS_HIGH, shape=(size,), dtype=np.float32)

    def get_state(self) -> Any:
        """See the class docstring."""
        vk = self.k.vehicle
        max_speed = self.k.network.max_speed()
        speeds = np.asarray(vk.speed, dtype=np.float64)
        pos = np.asarray(vk.lane_pos, dtype=np.float64)
        n_edges = len(self.edge_list)
        # each car's edge column (n_edges: an internal or unknown edge, a bin of its own)
        # and observed-edge slot (-1: none)
        col, slot = self._edge_columns(vk, speeds.size)
        # the num_observed cars nearest the junction on each observed edge, edge by edge
        # (one stable sort of all cars: by slot, then nearest first; the cars on no observed
        # edge, slot -1, come first and are cut off)
        k = self.num_observed
        order = np.lexsort((-pos, slot))
        s = slot[order]
        first = int(s.searchsorted(0))
        order, s = order[first:], s[first:]
        rank = np.arange(s.size) - s.searchsorted(s, side="left")
        kept = (rank < k).nonzero()[0]
        rows, s = order[kept], s[kept]
        dest = s * k + rank[kept]
        # one buffer, filled part by part in the observation's order
        per_car = self._slot_length.size * k
        at = 3 * per_car
        obs = np.zeros(at + 2 * n_edges + self.timers.packed.size)
        obs[:per_car][dest] = speeds[rows] / max_speed
        obs[per_car:at][dest] = (self._slot_length[s] - pos[rows]) / self.max_dist
        obs[2 * per_car : at][dest] = self._slot_num[s]
        ids = vk.table.ids
        self.observed_ids = [ids[r] for r in rows.tolist()]
        counts = np.bincount(col, minlength=n_edges + 1)[:n_edges]
        sums = np.bincount(col, weights=speeds, minlength=n_edges + 1)[:n_edges]
        density = obs[at : at + n_edges]
        np.divide(np.multiply(counts, VEHICLE_LENGTH, out=density), self._edge_len, out=density)
        velocity = obs[at + n_edges : at + 2 * n_edges]
        np.divide(sums, counts, out=velocity, where=counts > 0)
        velocity /= max_speed
        obs[at + 2 * n_edges :] = self.timers.packed
        # clipped to [0, OBS_HIGH] (np.clip's value, without its Python-level wrapper)
        np.minimum(np.maximum(obs, 0.0, out=obs), OBS_HIGH, out=obs)
        return obs.astype(np.float32)

    def _edge_columns(self, vk: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Each car's network-edge column (the number of edges for a junction-internal or
        unknown edge) and observed-edge slot (-1: none), by edge index."""
        index = vk.edge_index
        if index is None:
            other = len(self.edge_list)
            col = np.fromiter((self._edge_col.get(e, other) for e in vk.edges), np.int64, n)
            return col, self._slot_of_col[col]
        names = vk.edge_names
        if self._col_names is not names:  # a new lane table (a new episode)
            self._col_names = names
            other = len(self.edge_list)
            self._col_by_index = np.array([self._edge_col.get(e, other) for e in names], np.int64)
            self._slot_by_index = self._slot_of_col[self._col_by_index]
        return self._col_by_index[index], self._slot_by_index[index]

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """``-delay - 0.2 * standing cars`` (``-delay`` when evaluating)."""
        delay = rewards.min_delay_unscaled(self)
        if self.env_params.evaluate:
            return -delay
        standstill = rewards.penalize_standstill(self, gain=0.2)
        self.reward_terms = {"delay": -delay, "standstill": standstill}
        return -delay + standstill

    def additional_command(self) -> None:
        """Yellow timers, and Flow's marking of the observed cars (no re-insertion: Flow's
        PO env replaces its parent's command)."""
        self._advance_timers()
        self.k.vehicle.set_observed_many(self.observed_ids)


class TrafficLightGridBenchmarkEnv(TrafficLightGridPOEnv):
    """Flow's grid0/grid1 env: trains on the desired-velocity reward towards
    ``target_velocity`` (0 after a collision), evaluates on ``-delay``."""

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Desired velocity (``-delay`` when evaluating): Flow's ``rewards.desired_velocity``
        on every car, its formula called on the kernel's speeds directly."""
        if self.env_params.evaluate:
            return -rewards.min_delay_unscaled(self)
        speeds = self.k.vehicle.speed
        if speeds.size and speeds.min() < -100:  # Flow's guard against SUMO's error value
            return 0.0
        target = float(self.env_params.additional_params["target_velocity"])
        return formulas.desired_velocity(speeds, target, fail=bool(kwargs.get("fail", False)))


#: Flow's older name (``flow.envs.green_wave_env``).
PO_TrafficLightGridEnv = TrafficLightGridPOEnv

"""``TrafficLightGridEnv``: one agent switches every light of Flow's traffic-light grid.

The base of the partially observed and benchmark envs of :mod:`flowrun.envs.traffic_light_grid`
(Flow's module, which re-exports this one's names). One agent switches every light of a
``TrafficLightGridNetwork``. Each light has two greens (vertical: Flow's ``GrGr``,
horizontal: ``rGrG``); an action asks some lights to switch, which happens through
``switch_time`` seconds of yellow (:class:`~flowrun.envs.signals.SwitchTimers`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box, Discrete, Tuple

from flowrun.envs import flow_rewards as rewards
from flowrun.envs.base import Env
from flowrun.envs.signals import (
    SwitchRequests,
    SwitchTimers,
    discrete_mask,
    edge_number,
    phase_state,
    relative_node,
)
from flowrun.errors import ConfigError
from flowrun.networks.base import Network

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # seconds of yellow of a switch (Flow's "minimum switch time")
    "switch_time": 2.0,
    # "controlled": lights start vertical green and only RL switches them; "actuated":
    # they run the network's programs until the agent first switches them
    "tl_type": "controlled",
    # Discrete(2**n) actions instead of Box(n)
    "discrete": False,
}
_VERTICAL = ("left", "right")


def reentry_edges(rows: int, cols: int) -> dict[str, str]:
    """Flow's grid: each exit edge and the entry edge its cars re-enter on (the same row or
    column, the same heading): eastbound ``bot{i}_{cols}`` -> ``bot{i}_0``, westbound
    ``top{i}_0`` -> ``top{i}_{cols}``, southbound ``left0_{j}`` -> ``left{rows}_{j}``,
    northbound ``right{rows}_{j}`` -> ``right0_{j}``."""
    out = {f"bot{i}_{cols}": f"bot{i}_0" for i in range(rows)}
    out |= {f"top{i}_0": f"top{i}_{cols}" for i in range(rows)}
    out |= {f"left0_{j}": f"left{rows}_{j}" for j in range(cols)}
    out |= {f"right{rows}_{j}": f"right0_{j}" for j in range(cols)}
    return out


class TrafficLightGridEnv(Env):
    """Flow's ``TrafficLightGridEnv``: all lights of the grid switched by one agent.

    Observation: ``Tuple`` of four ``Box``es over the first ``N = initial vehicles`` cars
    (kernel order, zero-padded): speed / max speed, distance to the junction ahead / the
    longest edge length, Flow's edge number / (Flow's ``num_edges`` - 1); then the lights'
    ``last_change`` (s), ``direction`` and ``currently_yellow`` (``3 * n_lights``).
    Action: ``Box(-1, 1, (n_lights,))``, > 0 asks light ``center{i}`` to switch
    (``Discrete(2**n)`` with ``discrete``). Reward: ``-delay - (number of actions >= 0.5)``
    with Flow's ``min_delay_unscaled`` delay. Termination: collision; truncation: horizon.
    As Flow's, a car that reaches an exit edge is taken out and put back at the start of
    the entry edge of the same row or column, heading the same way (same id, type and lane,
    position 0, the lane's maximum speed), so the number of cars stays constant. (Flow's
    ``TrafficLightGridPOEnv`` and the benchmark env do not: their cars leave and inflows
    bring new ones.)
    """

    DEFAULT_EXPERIMENT = "grid0.yaml"  # Flow's grid0

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    @classmethod
    def check_network(cls, network: Network) -> None:
        """What this env needs of its network: at least one traffic light (``flowrun
        validate`` / ``baseline`` / ``train`` call this before a run, to name the YAML line).

        Raises:
            ConfigError: the network has no light, at the key to change.
        """
        if any(n.type == "traffic_light" for n in network.spec.nodes):
            return
        name = network.network_type or type(network).__name__
        head = f"{cls.__name__} switches traffic lights, but network '{name}' has none"
        if network.net_params.additional_params.get("traffic_lights") is False:
            raise ConfigError(
                f"{head} (traffic_lights: false); set network.traffic_lights: true",
                path="network.traffic_lights",
            )
        raise ConfigError(
            f"{head}; use network type traffic_light_grid, or put lights on its junctions "
            "under traffic_lights.lights",
            path="network.type",
        )

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.check_network(self.network)
        spec = self.network.spec
        self.light_ids = [n.id for n in spec.nodes if n.type == "traffic_light"]
        p = self.env_params.additional_params
        grid = self.net_params.additional_params.get("grid_array") or getattr(
            self.network, "grid_array", {}
        )
        self.rows = int(spec.extra.get("rows", grid.get("row_num", 1)))
        self.cols = int(spec.extra.get("cols", grid.get("col_num", len(self.light_ids))))
        self.num_traffic_lights = len(self.light_ids)
        self.tl_type = str(p["tl_type"])
        self.discrete = bool(p.get("discrete", False))
        self.min_switch_time = float(p["switch_time"])
        self.timers = SwitchTimers(self.num_traffic_lights, self.min_switch_time, self.sim_step)
        self.max_dist = max(e.length for e in spec.edges)
        self.num_edges = int(getattr(self.network, "num_edges", len(spec.edges)))
        self._vertical: list[list[bool]] = []
        self._phase_states: list[list[str]] = []
        self._acted = False
        self._reentry = reentry_edges(self.rows, self.cols)

    # Flow's attribute names
    @property
    def last_change(self) -> np.ndarray:
        """Seconds since each light's last switch began (as Flow, a column vector)."""
        return self.timers.last_change.reshape(-1, 1)

    @property
    def direction(self) -> np.ndarray:
        """0 vertical green, 1 horizontal green, per light."""
        return self.timers.direction.reshape(-1, 1)

    @property
    def currently_yellow(self) -> np.ndarray:
        """1 while the light is yellow."""
        return self.timers.currently_yellow.reshape(-1, 1)

    @property
    def action_space(self) -> Box | Discrete:  # type: ignore[override]
        """One switch request per light."""
        if self.discrete:
            return Discrete(2**self.num_traffic_lights)
        return Box(low=-1, high=1, shape=(self.num_traffic_lights,), dtype=np.float32)

    @property
    def observation_space(self) -> Tuple:  # type: ignore[override]
        """Speeds, distances, edge numbers of ``N`` cars, and the lights' features."""
        n = self.initial_vehicles.num_vehicles
        high = max(1.0, self.min_switch_time + self.sim_step)
        return Tuple((
            Box(0.0, 1.0, (n,), np.float32),
            Box(0.0, np.inf, (n,), np.float32),
            Box(0.0, 1.0, (n,), np.float32),
            Box(0.0, high, (3 * self.num_traffic_lights,), np.float32),
        ))  # fmt: skip

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """New episode: timers cleared; ``controlled`` lights start vertical green."""
        self.timers.reset()
        obs, info = super().reset(seed=seed, options=options)
        tk = self.k.traffic_light
        self._vertical = [
            [lane.split("_")[0].rstrip("0123456789").startswith(_VERTICAL) for lane in
             tk.get_controlled_lanes(t)] for t in self.light_ids
        ]  # fmt: skip
        # each light's four states, at 2 * direction + yellow
        self._phase_states = [
            [phase_state(v, d, y) for d in (0, 1) for y in (False, True)] for v in self._vertical
        ]
        if self.tl_type != "actuated":
            for i, light in enumerate(self.light_ids):
                tk.set_state(light, self._phase_states[i][0])
            obs = self._format_obs(self.get_state())
        return obs, info

    # ------------------------------------------------------------------ actions
    def _switch_mask(self, rl_actions: Any) -> SwitchRequests:
        if self.discrete:
            return discrete_mask(int(np.asarray(rl_actions).reshape(-1)[0]),
                                 self.num_traffic_lights)  # fmt: skip
        return np.asarray(rl_actions, dtype=np.float64).reshape(-1) > 0.0

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        self._update_lights(self._switch_mask(rl_actions))

    def _update_lights(self, switch: SwitchRequests) -> None:
        self._acted = True
        set_state, ids, states = self.k.traffic_light.set_state, self.light_ids, self._phase_states
        for i, direction, yellow in self.timers.step(switch):
            set_state(ids[i], states[i][2 * direction + yellow])

    def additional_command(self) -> None:
        """Yellow timers run on steps without an action too; cars on exit edges re-enter."""
        self._advance_timers()
        self._reinsert_exiting()

    def _advance_timers(self) -> None:
        if not self._acted:
            self._update_lights([False] * self.num_traffic_lights)
        self._acted = False

    def _reinsert_exiting(self) -> None:
        """Flow's ``_reroute_if_final_edge`` for every car: one on an exit edge goes back to
        the entry edge of its row or column (see the class docstring)."""
        vk, reentry = self.k.vehicle, self._reentry
        due = [(vid, reentry[e]) for vid, e in zip(vk.get_ids(), vk.edges, strict=True)
               if e in reentry]  # fmt: skip
        for veh_id, entry in due:
            type_id, lane = vk.get_type(veh_id), vk.get_lane(veh_id)
            vk.remove(veh_id)
            vk.add(veh_id, type_id=type_id, edge=entry, pos="0", lane=str(lane), speed="max")

    # ------------------------------------------------------------------ Flow's helpers
    def get_distance_to_intersection(self, veh_ids: str | list[str]) -> Any:
        """Distance (m) from a car (or each of a list) to the node its edge leads to, as
        Flow's: edge length minus lane position; 0 on a junction's link (``center`` in the
        edge id); -10 for a car not in the network."""
        if isinstance(veh_ids, list):
            return [self.get_distance_to_intersection(v) for v in veh_ids]
        edge = self.k.vehicle.get_edge(veh_ids)
        if edge == "":
            return -10.0
        if "center" in edge:
            return 0.0
        return self.k.network.edge_length(edge) - self.k.vehicle.get_position(veh_ids)

    def _split_edge(self, edge: str) -> int:
        """Flow's number of one grid edge: 1 to ``num_edges``, internal edges of ``center{k}``
        after the others, 0 for no edge (see :func:`~flowrun.envs.signals.edge_number`)."""
        return edge_number(edge, self.rows, self.cols)

    def _convert_edge(self, edges: list[str]) -> list[int]:
        """Flow's numbers of a list of grid edges (:meth:`_split_edge` of each)."""
        return [edge_number(e, self.rows, self.cols) for e in edges]

    def _get_relative_node(self, agent_id: str, direction: str) -> int:
        """Flow's index of the light next to light ``agent_id`` (``center{k}``) in
        ``direction`` (``top``, ``bottom``, ``left``, ``right``); -1 past the grid's edge.

        Raises:
            NotImplementedError: an unknown direction, as Flow's.
        """
        return relative_node(int(agent_id.split("center")[-1]), direction, self.rows, self.cols)

    def get_closest_to_intersection(
        self, edges: str | list[str], num_closest: int, padding: bool = False
    ) -> list[str]:
        """Ids of the ``num_closest`` cars nearest the end of each edge, nearest first (Flow's).

        For a list of edges the per-edge lists are joined in order. ``padding`` fills an edge
        with fewer cars up to ``num_closest`` with ``""`` (as Flow's code, only for one edge:
        a list is joined unpadded).

        Raises:
            ValueError: ``num_closest`` is not positive.
        """
        if num_closest <= 0:
            raise ValueError(
                f"get_closest_to_intersection: num_closest={num_closest}, expected a positive "
                "number of cars per edge"
            )
        if isinstance(edges, list):
            return [v for e in edges for v in self.get_closest_to_intersection(e, num_closest)]
        ids = sorted(self.k.vehicle.get_ids_by_edge(edges), key=self.get_distance_to_intersection)
        pad = [""] * (num_closest - len(ids)) if padding else []
        return ids[:num_closest] + pad

    # ------------------------------------------------------------------ observations
    def _car_columns(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Speed / max speed, distance to the junction / max_dist, edge number, per car."""
        vk, net = self.k.vehicle, self.k.network
        speeds = np.asarray(vk.speed, dtype=np.float64) / net.max_speed()
        edges = list(vk.edges)
        pos = np.asarray(vk.lane_pos, dtype=np.float64)
        length = np.array([net.edge_length(e) if e and not e.startswith(":") else 0.0
                           for e in edges])  # fmt: skip
        dist = np.where(length > 0, length - pos, 0.0) / self.max_dist
        nums = np.array([edge_number(e, self.rows, self.cols) for e in edges], dtype=np.float64)
        return speeds, dist, nums / max(self.num_edges - 1, 1)

    def get_state(self) -> Any:
        """See the class docstring."""
        n = self.initial_vehicles.num_vehicles
        cols = self._car_columns()
        parts = []
        for col, high in zip(cols, (1.0, np.inf, 1.0), strict=True):
            out = np.zeros(n, dtype=np.float32)
            k = min(n, col.size)
            out[:k] = np.clip(col[:k], 0.0, high)
            parts.append(out)
        space = self.observation_space.spaces[3]
        assert isinstance(space, Box)
        lights = np.clip(self.timers.features(), 0.0, space.high).astype(np.float32)
        return (parts[0], parts[1], parts[2], lights)

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """``-delay - number of switch requests >= 0.5`` (Flow)."""
        delay = rewards.min_delay_unscaled(self)
        if rl_actions is None:
            return -delay
        mask = self._switch_mask(rl_actions) if self.discrete else \
            np.asarray(rl_actions, dtype=np.float64).reshape(-1) >= 0.5  # fmt: skip
        penalty = rewards.boolean_action_penalty(mask, gain=1.0)
        self.reward_terms = {"delay": -delay, "switch_penalty": -penalty}
        return -delay - penalty


class TrafficLightGridTestEnv(TrafficLightGridEnv):
    """Flow's test variant: actions do nothing, reward 0."""

    __test__ = False

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        """Nothing."""

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """0."""
        return 0.0


#: Flow's older names (``flow.envs.green_wave_env``).
GreenWaveTestEnv = TrafficLightGridTestEnv

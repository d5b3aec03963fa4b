"""``MultiTrafficLightGridPOEnv``: each light of the grid is an agent (Flow's multi-agent grid).

Flow's ``flow.envs.multiagent.traffic_light_grid``: :class:`TrafficLightGridPOEnv`'s signal
control split per light, as a PettingZoo ``ParallelEnv``. The agents are the lights
(``center0 .. center{n-1}``); they are all present for the whole episode.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box, Discrete

from flowrun.envs import flow_rewards as rewards
from flowrun.envs.signals import relative_node
from flowrun.envs.traffic_light_grid import TrafficLightGridPOEnv
from flowrun.errors import ConfigError
from flowrun.multiagent.base import MultiAgentEnv

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # lights each agent sees besides itself (Flow: 4, its neighbours; only 4 is implemented)
    "num_local_lights": 4,
    # edges each agent sees (Flow: 4, its incoming edges; only 4 is implemented)
    "num_local_edges": 4,
}

#: Flow's upper bound of every observed value of the multi-agent grid.
OBS_HIGH = 5.0
#: Neighbours in Flow's order (``_get_relative_node``).
NEIGHBOURS = ("top", "bottom", "left", "right")


class MultiTrafficLightGridPOEnv(MultiAgentEnv, TrafficLightGridPOEnv):
    """One agent per traffic light of the grid (Flow's ``MultiTrafficLightGridPOEnv``).

    Agents: the lights ``center{i}`` (``possible_agents`` = ``agents`` for the whole episode).

    Observation (per agent, ``Box(0, 5)``, ``12 * num_observed + 18`` values, Flow's order):
    for each of the light's 4 incoming edges (from the left, below, the right, above) the
    ``num_observed`` cars nearest the junction: their speeds / max speed, then distances to
    the junction / the longest edge, then Flow's edge numbers / (``num_edges`` - 1); missing
    cars are padded as Flow does (speed 1, distance 1, edge 0). Then the 4 incoming edges'
    density (``5 m * cars / length``) and mean speed / max speed; then the ``direction`` and
    the ``currently_yellow`` flag of the light itself and of its neighbours above, below, left
    and right (a missing neighbour reads direction 0, yellow 1).
    Action (per agent): ``Box(-1, 1, (1,))``, > 0 asks the light to switch (through
    ``switch_time`` s of yellow; requests while yellow are ignored); ``Discrete(2)`` (1 =
    switch) with ``discrete``. A light without an action this step is not switched, but its
    yellow timer runs (Flow's froze it).
    Reward (shared): ``(-delay - 0.2 * cars standing still) / number of lights`` (Flow's
    ``min_delay_unscaled`` and ``penalize_standstill``); ``-delay / number of lights`` in
    evaluate mode. Terms in ``info["reward_terms"]``.
    Termination: a collision (all agents); truncation: the horizon (all agents).
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {
        **TrafficLightGridPOEnv.ADDITIONAL_ENV_PARAMS,
        **ADDITIONAL_ENV_PARAMS,
    }

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        params = self.env_params.additional_params
        for key in ADDITIONAL_ENV_PARAMS:
            if params[key] != 4:
                raise ConfigError(
                    f"only 4 is implemented (as in Flow), got {params[key]!r}",
                    path=f"env.additional_params.{key}",
                )
        self.num_local_lights = 4
        self.num_local_edges = 4
        # agents are the lights, not RL vehicles: replace what the base derived from vehicles
        self.possible_agents = list(self.light_ids)
        self._possible = frozenset(self.possible_agents)
        self.observation_spaces = dict.fromkeys(self.possible_agents, self._obs_space)
        self.action_spaces = dict.fromkeys(self.possible_agents, self._act_space)
        self._light_index = {light: i for i, light in enumerate(self.light_ids)}
        mapping = dict(self.node_mapping)
        #: per light: its 4 incoming edges' columns in the edge table
        self._local_cols = np.array(
            [[self._edge_col[e] for e in mapping[light]] for light in self.light_ids],
            dtype=np.int64,
        )
        number = {light: int(light.removeprefix("center")) for light in self.light_ids}
        by_number = {v: self._light_index[k] for k, v in number.items()}
        n = len(self.light_ids)
        #: per light: itself and its neighbours top/bottom/left/right (n: the padding entry)
        self._local_lights = np.array(
            [
                [self._light_index[light]]
                + [
                    by_number.get(relative_node(number[light], s, self.rows, self.cols), n)
                    for s in NEIGHBOURS
                ]
                for light in self.light_ids
            ],
            dtype=np.int64,
        )

    # ------------------------------------------------------------------ spaces
    @property
    def agent_observation_space(self) -> Box:
        """``12 * num_observed + 18`` values in [0, 5] (see the class docstring)."""
        size = 3 * 4 * self.num_observed + 2 * 4 + 2 * (1 + 4)
        return Box(low=0.0, high=OBS_HIGH, shape=(size,), dtype=np.float32)

    @property
    def agent_action_space(self) -> Box | Discrete:  # type: ignore[override]
        """One switch request in [-1, 1] (> 0 switches), or ``Discrete(2)`` with ``discrete``."""
        if self.discrete:
            return Discrete(2)
        return Box(low=-1.0, high=1.0, shape=(1,), dtype=np.float32)

    # ------------------------------------------------------------------ agents
    def _sync_agents(self) -> tuple[set[str], list[str]]:
        """The lights are the agents from reset to the end of the episode."""
        if self.agents:
            return set(), []
        self.agents = list(self.possible_agents)
        return set(), list(self.agents)

    def _clip(self, action: Any) -> Any:
        if self.discrete:
            return int(np.asarray(action).reshape(-1)[0])
        return super()._clip(action)

    # ------------------------------------------------------------------ dynamics
    def _apply_rl_actions(self, rl_actions: Any) -> None:
        """Switch requests of the lights that acted; every light's yellow timer runs."""
        switch = np.zeros(self.num_traffic_lights, dtype=bool)
        for light, action in rl_actions.items():
            i = self._light_index[light]
            if self.discrete:
                switch[i] = int(action) == 1
            else:
                switch[i] = float(np.asarray(action).reshape(-1)[0]) > 0.0
        self._update_lights(switch)

    def get_state(self) -> dict[str, Any]:
        """Each light's local cars, local edges and its and its neighbours' signal flags."""
        flat = TrafficLightGridPOEnv.get_state(self)  # also sets observed_ids for the GUI
        per_edge = 4 * self.num_observed
        n_lights = self.num_traffic_lights
        blocks = 3 * per_edge * n_lights
        cars = flat[:blocks].reshape(3, n_lights, per_edge).astype(np.float64)
        n_edges = len(self.edge_list)
        density = flat[blocks : blocks + n_edges]
        velocity = flat[blocks + n_edges : blocks + 2 * n_edges]
        # padding as Flow's multi-agent grid: an empty slot (edge number 0; every observed
        # car stands on a numbered edge) reads as a fast (1) and far (1) car
        empty = cars[2] <= 0.0
        cars[0][empty] = 1.0
        cars[1][empty] = 1.0
        direction = np.append(self.timers.direction, 0.0)
        yellow = np.append(self.timers.currently_yellow, 1.0)
        order = {light: k for k, (light, _) in enumerate(self.node_mapping)}
        obs = {}
        for light in self.agents:
            i = self._light_index[light]
            k = order[light]
            cols, near = self._local_cols[i], self._local_lights[i]
            obs[light] = np.concatenate([
                cars[0, k], cars[1, k], cars[2, k], density[cols], velocity[cols],
                direction[near], yellow[near],
            ])  # fmt: skip
        return obs

    def compute_reward(  # type: ignore[override]  # {} without actions, as Flow's
        self, rl_actions: Any, **kwargs: Any
    ) -> float | dict[str, float]:
        """Flow's shared delay reward divided by the number of lights; ``{}`` for no actions
        (Flow's warm-up steps)."""
        if rl_actions is None:
            return {}
        delay = rewards.min_delay_unscaled(self)
        if self.env_params.evaluate:
            return -delay / self.num_traffic_lights
        standstill = rewards.penalize_standstill(self, gain=0.2)
        self.reward_terms = {"delay": -delay, "standstill": standstill}
        return (-delay + standstill) / self.num_traffic_lights

"""``BottleneckEnv``: the bottleneck's base environment (Flow's ``flow.envs.bottleneck``).

Vinitsky, Parvate, Kreidieh, Wu, Hu, Bayen, "Lagrangian Control through Deep-RL:
Applications to Bottleneck Decongestion", IEEE ITSC 2018. On Flow's
:class:`~flowrun.networks.bottleneck.BottleneckNetwork` four lanes narrow to two and then to
one; past about 1,600 veh/h of inflow (scaling 1) the merges break down and the outflow
*drops* below capacity. The RL envs (:mod:`flowrun.envs.bottleneck_accel`,
:mod:`flowrun.envs.bottleneck_velocity`) build on this one.
"""

from __future__ import annotations

from collections import deque
from typing import Any, ClassVar

import numpy as np
from gymnasium.spaces import Box

from flowrun.envs.base import Env
from flowrun.errors import ConfigError

#: Flow's constants: the largest number of lanes per unit of ``scaling``, the edges in
#: driving order, the length of the bottleneck (edge ``4``, m), and the vehicle count
#: and speed (m/s) that normalise observations.
MAX_LANES = 4
EDGE_LIST = ("1", "2", "3", "4", "5")
BOTTLENECK_LEN = 280.0
NUM_VEHICLE_NORM = 20.0

ADDITIONAL_ENV_PARAMS: dict[str, Any] = {
    # maximum acceleration of the AVs, m/s^2
    "max_accel": 3,
    # maximum deceleration of the AVs, m/s^2
    "max_decel": 3,
    # steps an AV waits after a lane change before it may change again (Flow's counter
    # counts simulation steps although its comment says seconds)
    "lane_change_duration": 5,
    # Flow's toll booth on node 2 (disabled; flowrun has no toll booth: must stay true)
    "disable_tb": True,
    # Flow's ALINEA ramp meter on node 3 (disabled; flowrun has none: must stay true)
    "disable_ramp_metering": True,
}


def check_disabled(params: dict[str, Any]) -> None:
    """Refuse Flow's toll booth and ramp meter, which flowrun does not model.

    Raises:
        ConfigError: ``disable_tb`` or ``disable_ramp_metering`` is not true.
    """
    for key, what in (("disable_tb", "toll booth"), ("disable_ramp_metering", "ramp meter")):
        if params.get(key, True) is not True:
            raise ConfigError(
                f"flowrun's bottleneck has no {what} (Flow's is off by default too); "
                f"set {key}: true",
                path=f"env.additional_params.{key}",
            )


class BottleneckEnv(Env):
    """The bottleneck without an agent (Flow's ``BottleneckEnv``): what ``flowrun baseline``
    runs on the bottleneck, and the base of the RL bottleneck envs.

    Observation: Flow's dummy ``[1]`` (``Box(-inf, inf, (1,))``). Action: none used
    (``Box(-inf, inf, (1,))``). Reward: the outflow over the last ``10 * sim_step`` s
    divided by ``2000 * scaling`` veh/h. Termination: collision; truncation: horizon.
    ``info`` adds ``outflow`` (veh/h over the last ``10 * sim_step`` s) to the base's keys.
    Flow's ``smoothed_num`` (cars on edge ``4`` over the last 10 steps) is kept current.
    """

    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_ENV_PARAMS

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        check_disabled(self.env_params.additional_params)
        #: Flow's factor multiplying the number of lanes
        self.scaling = int(self.net_params.additional_params.get("scaling", 1))
        #: cars on the bottleneck edge ``4`` at each of the last 10 simulation steps
        self.smoothed_num: deque[int] = deque([0] * 10, maxlen=10)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Start a new episode (the edge-``4`` counts start at zero)."""
        self.smoothed_num = deque([0] * 10, maxlen=10)
        return super().reset(seed=seed, options=options)

    @property
    def action_space(self) -> Box:  # type: ignore[override]
        """Flow's dummy action space."""
        return Box(low=-np.inf, high=np.inf, shape=(1,), dtype=np.float32)

    @property
    def observation_space(self) -> Box:  # type: ignore[override]
        """Flow's dummy observation space."""
        return Box(low=-np.inf, high=np.inf, shape=(1,), dtype=np.float32)

    def _apply_rl_actions(self, rl_actions: Any) -> None:
        """No agent acts here."""

    def get_state(self) -> Any:
        """Flow's dummy observation ``[1]``."""
        return np.ones(1)

    def additional_command(self) -> None:
        """Count the cars in the bottleneck (edge ``4``) for :meth:`get_bottleneck_density`."""
        self.smoothed_num.append(len(self.k.vehicle.get_ids_by_edge("4")))

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """Outflow over the last ``10 * sim_step`` s, normalised by ``2000 * scaling``."""
        return self.k.vehicle.get_outflow_rate(10 * self.sim_step) / (2000.0 * self.scaling)

    def get_bottleneck_density(self, lanes: list[str] | None = None) -> float:
        """Cars per metre on edges ``3`` and ``4`` (only on ``lanes``, ids ``"edge_lane"``,
        if given), over Flow's bottleneck length of 280 m."""
        vk = self.k.vehicle
        ids = vk.get_ids_by_edge(["3", "4"])
        if lanes:
            ids = [v for v in ids if f"{vk.get_edge(v)}_{vk.get_lane(v)}" in lanes]
        return len(ids) / BOTTLENECK_LEN

    def _info(self, crash: bool) -> dict[str, Any]:
        info = super()._info(crash)
        info["outflow"] = self.k.vehicle.get_outflow_rate(10 * self.sim_step)
        return info

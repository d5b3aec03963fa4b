"""The ``traffic_lights:`` section: declared signal programs and the baseline signal controller.

``programs`` are Flow's :class:`~flowrun.config.traffic_lights.TrafficLightParams`;
``controller`` names a non-RL signal baseline that ``flowrun baseline`` runs instead:

* ``fixed_time``: every light a static program, Flow's phase lengths (31 s of green per
  direction, ``yellow`` s of yellow between).
* ``actuated``: SUMO's gap-actuated program, Flow's ``TrafficLightParams(baseline=True)``.
* ``max_pressure``: switched every step by pressure (Varaiya 2013), at least ``min_green`` s of
  green, ``yellow`` s of yellow; see :mod:`flowrun.experiment.signal_baselines`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from flowrun.config.traffic_lights import TrafficLightParams

#: The signal controllers ``traffic_lights.controller`` may name.
CONTROLLERS = ("fixed_time", "actuated", "max_pressure")
#: Default shortest green of max-pressure, s.
MIN_GREEN = 8.0
#: Default yellow of fixed-time and max-pressure switches, s.
YELLOW = 3.0
#: Green of each direction of the fixed-time program, s (Flow's grid phase length).
FIXED_GREEN = 31.0


@dataclass(frozen=True)
class TrafficLightsConfig:
    """``traffic_lights:`` section.

    YAML ``traffic_lights: {baseline: false, lights: [{node_id: center0, phases: [...]}]}``
    is ``TrafficLightsConfig(TrafficLightParams(...))``.

    Attributes:
        programs: the declared programs (Flow's ``TrafficLightParams``; YAML ``baseline`` and
            ``lights``, each light the arguments of ``TrafficLightParams.add``).
        controller: ``fixed_time``, ``actuated`` or ``max_pressure`` to run that signal
            baseline on every light (``None``: the declared programs).
        min_green: shortest green of ``max_pressure``, s.
        yellow: yellow of a switch of ``fixed_time`` and ``max_pressure``, s.
    """

    programs: TrafficLightParams = field(default_factory=TrafficLightParams)
    controller: str | None = None
    min_green: float = MIN_GREEN
    yellow: float = YELLOW

    @property
    def is_default(self) -> bool:
        """Nothing declared: the network's own (netconvert's) programs run."""
        return self == TrafficLightsConfig()


def controller_programs(
    controller: str, lights: Sequence[str], yellow: float
) -> TrafficLightParams:
    """The programs a signal controller loads (max-pressure: SUMO's default, then overridden)."""
    if controller == "actuated":
        return TrafficLightParams(baseline=True)
    tl = TrafficLightParams()
    if controller == "fixed_time":
        phases = [
            {"duration": FIXED_GREEN, "state": "GrGr"},
            {"duration": yellow, "state": "yryr"},
            {"duration": FIXED_GREEN, "state": "rGrG"},
            {"duration": yellow, "state": "ryry"},
        ]
        for light in lights:
            tl.add(light, phases=phases)
    return tl


def network_programs(tls: TrafficLightsConfig, lights: Sequence[str]) -> TrafficLightParams:
    """What the network loads: the controller's programs when one is named, else the declared."""
    if tls.controller is None:
        return tls.programs
    return controller_programs(tls.controller, lights, tls.yellow)

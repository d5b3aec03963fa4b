"""What the numpy backend runs, read once from a config — or one clear refusal.

:func:`ring_plan` is the only place that decides whether ``sim.backend: numpy`` can run a
config: single-lane rings, the ring envs :data:`SUPPORTED_ENVS`, stateless controllers with a
pure formula, ``ContinuousRouter`` on every car, one simulation step per env step, SUMO's IDM
for the cars SUMO itself drives, and speed modes whose "max accel/decel" bits are clear.
Anything else is a :class:`~flowrun.errors.ConfigError` before anything runs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from flowrun.config.model import ExperimentConfig
from flowrun.config.vehicles import VehicleType
from flowrun.controllers.base import AccelerationController
from flowrun.envs.factory import env_class, make_network
from flowrun.envs.ring.accel import AccelEnv
from flowrun.envs.ring.wave_attenuation import (
    WaveAttenuationEnv,
    WaveAttenuationPOEnv,
    ring_bounds,
)
from flowrun.envs.vehicles import build_controllers
from flowrun.errors import ConfigError
from flowrun.fastring.physics import DEFAULT_EMERGENCY_DECEL
from flowrun.networks.base import Network
from flowrun.types import FloatArray

#: env classes the numpy backend reproduces, by the kind of observation/reward it computes
SUPPORTED_ENVS: dict[type, str] = {
    WaveAttenuationPOEnv: "wave_po",
    WaveAttenuationEnv: "wave",
    AccelEnv: "accel",
}

#: SUMO speed-mode bits 1 and 2: "regard maximum acceleration / deceleration" (not modelled)
_ACCEL_BITS = 0b110


@dataclass(frozen=True)
class GroupPlan:
    """One vehicle group: its rows ``[start, stop)`` and controller."""

    name: str
    start: int
    stop: int
    controller: AccelerationController

    @property
    def is_rl(self) -> bool:
        """Whether the agent drives this group."""
        return bool(self.controller.is_rl)


@dataclass(frozen=True)
class RingPlan:
    """Static facts of a config the numpy backend runs (per-car arrays have ``N`` entries).

    Attributes:
        cfg: the experiment.
        network: the config's ring (its ``start_positions`` places the cars, as on SUMO).
        kind: the env's observation/reward kind (a value of :data:`SUPPORTED_ENVS`).
        groups: the vehicle groups in row order.
        dt: simulation step, s.
        speed_limit: the ring's speed limit, m/s.
        lengths, min_gap, accel, decel, emergency_decel, tau, max_speed, des_speed: per-car
            vehicle-type facts (SUMO's meaning; ``des_speed`` is the car's maximum lane speed).
        safe_cap: per car, whether SUMO caps its commands by its safe speed (speed-mode bit 0).
        rl_rows: rows of the RL cars, in id order.
        noisy: per group with noise, ``(start, stop, noise)`` in group order (the order of
            the random draws).
        bounds: ``(low, high)`` of the ring length drawn at each reset, or ``None``.
        horizon, warmup: env steps per episode and warm-up steps at each reset.
        max_accel, max_decel: the action bounds, m/s^2.
        target_velocity: AccelEnv's reward target, m/s (``None`` for other kinds).
        evaluate, clip_actions: ``env.evaluate`` and ``env.clip_actions``.
    """

    cfg: ExperimentConfig
    network: Network
    kind: str
    groups: tuple[GroupPlan, ...]
    dt: float
    speed_limit: float
    lengths: FloatArray
    min_gap: FloatArray
    accel: FloatArray
    decel: FloatArray
    emergency_decel: FloatArray
    tau: FloatArray
    max_speed: FloatArray
    des_speed: FloatArray
    safe_cap: np.ndarray
    rl_rows: np.ndarray
    noisy: tuple[tuple[int, int, float], ...]
    bounds: tuple[int, int] | None
    horizon: int
    warmup: int
    max_accel: float
    max_decel: float
    target_velocity: float | None
    evaluate: bool
    clip_actions: bool

    @property
    def num_cars(self) -> int:
        """Cars per ring."""
        return int(self.lengths.size)

    @property
    def num_noisy(self) -> int:
        """Random draws per ring and simulation step."""
        return sum(stop - start for start, stop, _ in self.noisy)

    @property
    def max_length(self) -> float:
        """The largest ring length an episode can have, m."""
        if self.bounds is not None:
            return float(self.bounds[1])
        return float(self.network.spec.length)


class NumpyBackendRefusal(ConfigError):
    """A config the numpy backend cannot run: ``what`` it cannot do, at the key ``path``."""

    def __init__(self, what: str, path: str, source: str) -> None:
        self.what = what
        super().__init__(
            f"sim.backend numpy {what}; use sim.backend: sumo for this config", path, source
        )


def _refuse(what: str, path: str, source: str | None) -> NumpyBackendRefusal:
    return NumpyBackendRefusal(what, path, source or "")


def _controller_ok(c: AccelerationController) -> bool:
    """A controller the backend can run: the agent's, or a stateless pure formula."""
    if c.is_rl:
        return True
    return (
        c.commands_sumo
        and not c.stateful
        and not c.fail_safe
        and type(c).get_accel is AccelerationController.get_accel
    )


def ring_plan(cfg: ExperimentConfig) -> RingPlan:
    """Check that the numpy backend can run ``cfg`` and gather what it needs.

    Raises:
        ConfigError: one message naming the first thing the backend cannot do.
    """
    kind = _supported_kind(cfg)
    network = make_network(cfg)
    controls = build_controllers(cfg.vehicles)
    speed_limit = float(cfg.network.net_params.additional_params.get("speed_limit", 30))
    cars = _Cars()
    for i, (g, ctl) in enumerate(zip(cfg.vehicles.groups, controls, strict=True)):
        _check_group(f"vehicles[{i}]", g, ctl.controller, cfg.source)
        cars.add(g, ctl.controller, speed_limit)
    if cars.row < 2:
        raise _refuse("needs at least two cars on the ring", "vehicles", cfg.source)
    add = cfg.env.additional_params
    return RingPlan(
        cfg=cfg,
        network=network,
        kind=kind,
        groups=tuple(cars.groups),
        dt=float(cfg.sim.sim_step),
        speed_limit=speed_limit,
        lengths=cars.array("length"),
        min_gap=cars.array("min_gap"),
        accel=cars.array("accel"),
        decel=cars.array("decel"),
        emergency_decel=cars.array("emergency"),
        tau=cars.array("tau"),
        max_speed=cars.array("max_speed"),
        des_speed=cars.array("des"),
        safe_cap=cars.array("cap") > 0,
        rl_rows=np.array(cars.rl_rows, dtype=np.int64),
        noisy=tuple(cars.noisy),
        bounds=ring_bounds(add) if kind in ("wave", "wave_po") else None,
        horizon=int(cfg.env.horizon),
        warmup=int(cfg.env.warmup_steps),
        max_accel=float(add.get("max_accel", 1.0)),
        max_decel=abs(float(add.get("max_decel", 1.0))),
        target_velocity=float(add["target_velocity"]) if kind == "accel" else None,
        evaluate=bool(cfg.env.evaluate),
        clip_actions=bool(cfg.env.clip_actions),
    )


def _supported_kind(cfg: ExperimentConfig) -> str:
    """The kind of the config's env (:data:`SUPPORTED_ENVS`), once the env, network,
    simulation and episode settings are ones the backend runs."""
    src = cfg.source
    cls = env_class(cfg)
    kind = SUPPORTED_ENVS.get(cls)
    if kind is None:
        names = ", ".join(c.__name__ for c in SUPPORTED_ENVS)
        raise _refuse(f"runs the env classes {names}, not {cls.__name__}", "env.class", src)
    if cfg.network.type != "ring":
        raise _refuse(f"runs ring networks only, not {cfg.network.type!r}", "network.type", src)
    if int(cfg.network.net_params.additional_params.get("lanes", 1)) != 1:
        raise _refuse("runs single-lane rings only", "network.lanes", src)
    if cfg.sim.use_ballistic:
        raise _refuse("uses SUMO's Euler update only", "sim.use_ballistic", src)
    if cfg.env.sims_per_step != 1:
        raise _refuse("runs one simulation step per env step", "env.sims_per_step", src)
    if cfg.initial.spacing == "custom" or cfg.initial.edges_distribution != "all":
        raise _refuse("places cars with uniform or random spacing only", "initial", src)
    if kind == "accel" and cfg.env.additional_params.get("sort_vehicles"):
        raise _refuse("does not sort AccelEnv's observation", "env.additional_params", src)
    if kind == "accel" and cfg.env.additional_params.get("relative_positions"):
        where = "env.additional_params.relative_positions"
        raise _refuse("observes AccelEnv's absolute positions only", where, src)
    if not np.isfinite(cfg.env.horizon):
        raise _refuse("needs a finite env.horizon", "env.horizon", src)
    return kind


def _check_group(
    where: str, g: VehicleType, c: AccelerationController, src: str | None
) -> None:
    """Refuse a vehicle group (at ``where``) whose controller, router or car-following
    settings the backend does not model."""
    if not _controller_ok(c):
        raise _refuse(
            f"runs RLController and stateless pure car-following formulas without "
            f"fail-safes; group {g.veh_id!r} has {type(c).__name__}",
            f"{where}.acceleration_controller",
            src,
        )
    router = g.routing_controller.type if g.routing_controller else None
    if router != "ContinuousRouter":
        raise _refuse(
            f"needs ContinuousRouter on every car; group {g.veh_id!r} has {router}",
            f"{where}.routing_controller",
            src,
        )
    cf = g.car_following_params
    mode = int(cf.speed_mode)
    if mode & _ACCEL_BITS:
        raise _refuse(
            f"models speed modes without SUMO's max-accel/decel checks (0, 1, 25); "
            f"group {g.veh_id!r} has {mode}",
            f"{where}.car_following.speed_mode",
            src,
        )
    if (c.is_rl or mode & 1) and cf.car_follow_model != "IDM":
        raise _refuse(
            f"models SUMO's IDM for the cars SUMO drives or caps; group {g.veh_id!r} "
            f"has carFollowModel {cf.car_follow_model}",
            f"{where}.car_following.car_follow_model",
            src,
        )
    if cf.speed_dev != 0:
        raise _refuse("needs speed_dev 0", f"{where}.car_following.speed_dev", src)


class _Cars:
    """The per-car facts of the groups added so far, in row order."""

    KEYS = ("length", "min_gap", "accel", "decel", "emergency", "tau", "max_speed", "des", "cap")

    def __init__(self) -> None:
        self.groups: list[GroupPlan] = []
        self.facts: dict[str, list[float]] = {k: [] for k in self.KEYS}
        self.rl_rows: list[int] = []
        self.noisy: list[tuple[int, int, float]] = []
        self.row = 0

    def add(self, g: VehicleType, c: AccelerationController, speed_limit: float) -> None:
        """The group ``g`` driven by ``c``: its rows, and its vehicle type's facts per car
        (``des``: the car's maximum lane speed, m/s; ``cap``: speed-mode bit 0)."""
        cf, n, row = g.car_following_params, g.num_vehicles, self.row
        self.groups.append(GroupPlan(g.veh_id, row, row + n, c))
        if c.is_rl:
            self.rl_rows.extend(range(row, row + n))
        elif c.noise > 0:
            self.noisy.append((row, row + n, float(c.noise)))
        values = {
            "length": cf.length, "min_gap": cf.min_gap, "accel": cf.accel, "decel": cf.decel,
            "emergency": max(DEFAULT_EMERGENCY_DECEL, float(cf.decel)), "tau": cf.tau,
            "max_speed": cf.max_speed,
            "des": min(speed_limit * float(cf.speed_factor), float(cf.max_speed)),
            "cap": float(int(cf.speed_mode) & 1),
        }  # fmt: skip
        for key, value in values.items():
            self.facts[key].extend([float(value)] * n)
        self.row += n

    def array(self, key: str) -> FloatArray:
        """One fact of every car, ``(N,)``."""
        return np.array(self.facts[key], dtype=np.float64)


def check_numpy_backend(cfg: ExperimentConfig) -> None:
    """Raise :class:`ConfigError` when ``cfg`` asks for the numpy backend and it cannot run it."""
    if cfg.sim.backend == "numpy":
        ring_plan(cfg)


def refuse_numpy_backend(cfg: ExperimentConfig, command: str) -> None:
    """Raise :class:`ConfigError` when ``cfg`` asks for the numpy backend: ``command`` runs on
    SUMO only (the numpy backend serves training; its rings equal SUMO's to 1e-9 m/s)."""
    if cfg.sim.backend == "numpy":
        raise ConfigError(
            f"{command} runs on SUMO only; sim.backend numpy serves flowrun train. Add "
            "--set sim.backend=sumo (same trajectories: the backends agree to 1e-9 m/s)",
            "sim.backend",
            cfg.source or "",
        )


def describe(plan: RingPlan) -> dict[str, Any]:
    """A few facts of a plan, for logs and the benchmark."""
    return {
        "env": plan.kind,
        "cars": plan.num_cars,
        "rl": int(plan.rl_rows.size),
        "noisy": plan.num_noisy,
        "bounds": plan.bounds,
        "horizon": plan.horizon,
        "warmup": plan.warmup,
    }

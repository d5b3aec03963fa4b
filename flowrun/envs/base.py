"""``Env``: Flow's environment base class, as a Gymnasium environment.

Subclasses define (as in Flow's tutorial) the ``action_space`` and ``observation_space``
properties, ``_apply_rl_actions(rl_actions)``, ``get_state()`` and
``compute_reward(rl_actions, **kwargs)``, and optionally ``additional_command()``.
The base does the bookkeeping: seeded resets to the initial configuration, warm-up steps,
``sims_per_step``, action clipping, human-driver controllers, collision checks, and
``terminated`` (collision) vs ``truncated`` (horizon).
"""

from __future__ import annotations

import contextlib
import logging
import shutil
import tempfile
from abc import ABCMeta, abstractmethod
from collections import deque
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import gymnasium
import numpy as np

from flowrun.config.params import EnvParams, SumoParams
from flowrun.controllers.drivers import FlowStyleDriver, GroupRouters, bind_per_vehicle_groups
from flowrun.controllers.per_vehicle import PerVehicleGroup
from flowrun.envs.additional_params import check_additional_params as check_additional_params
from flowrun.envs.additional_params import check_env_arguments
from flowrun.envs.output import GREY as GREY
from flowrun.envs.output import EnvOutput
from flowrun.envs.spaces import ActionClipper
from flowrun.envs.vehicles import (
    FlowControllers,
    GroupControl,
    build_controllers,
    build_table,
)
from flowrun.networks.base import Network

if TYPE_CHECKING:  # the kernel, frames and painter are imported where an env starts
    from flowrun.envs.frames import StepRecord
    from flowrun.envs.render import EnvPainter
    from flowrun.kernel import Kernel
    from flowrun.kernel.geometry import RingPlacement

log = logging.getLogger(__name__)


class Env(EnvOutput, gymnasium.Env, metaclass=ABCMeta):
    """Base class of flowrun environments (Flow's ``flow.envs.Env``).

    Args:
        env_params: environment settings (horizon, warm-up, additional_params, ...).
        sim_params: simulation settings (step, seed, render).
        network: the network with its vehicles and initial placement.
        simulator: accepted for Flow compatibility (``"traci"``); libsumo always runs
            headless, sumo-gui over TraCI when ``sim_params.render`` and a display exist.
        render_mode: ``None`` or ``"rgb_array"`` (a top-down picture of the road and cars).
        work_dir: folder for generated SUMO files; a private temporary folder by default.

    Episode: ``reset`` restarts SUMO with the initial configuration (perturbation drawn from
    the env's seeded generator) and runs ``warmup_steps`` steps without RL actions. Each
    ``step`` runs ``sims_per_step`` simulation steps. ``terminated`` is true after a
    collision, ``truncated`` after ``horizon`` steps. Actions are clipped to a ``Box``
    action space (``clip_actions``) before they are applied and rewarded. ``info`` holds
    ``crash``, ``mean_speed``, ``collisions``, ``teleports``, ``time`` and the reward terms in
    ``reward_terms``. ``step`` raises ``gymnasium.error.ResetNeeded`` before the first
    ``reset``, after the episode ended, and after another env in this process started its
    own simulation (libsumo runs one per process).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012 - gymnasium's
    ADDITIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {}
    #: ``additional_params`` keys the env reads when given, with the default it uses when
    #: not (flowrun's options and Flow's optional keys): no config needs them, but a key one
    #: edit off one of them is refused as a typo.
    OPTIONAL_ENV_PARAMS: ClassVar[dict[str, Any]] = {}
    #: The experiment this env comes with, which ``gymnasium.make("flowrun/<Name>-v0")`` runs
    #: without a config: a file of the repository's ``configs/`` folder (see
    #: :func:`flowrun.envs.factory.default_experiment`); ``None``: Flow's ring task.
    DEFAULT_EXPERIMENT: ClassVar[str | None] = None

    def __init__(
        self,
        env_params: EnvParams,
        sim_params: SumoParams,
        network: Network | None = None,
        simulator: str = "traci",
        scenario: Network | None = None,
        render_mode: str | None = None,
        work_dir: Path | None = None,
    ) -> None:
        network = check_env_arguments(
            type(self), env_params, sim_params, network if network is not None else scenario,
            render_mode,
        )  # fmt: skip
        self.env_params = env_params
        self.sim_params = sim_params
        self.network = network
        self.scenario = network  # Flow < 0.5 name
        self.initial_network = network
        self.initial_vehicles = network.vehicles
        self.initial_config = network.initial_config
        self.net_params = network.net_params
        self.sim_step = sim_params.sim_step
        self.simulator = simulator
        self.render_mode = render_mode
        if isinstance(sim_params.render, str) and render_mode is None:
            self.render_mode = "rgb_array"  # Flow's frame modes (render="drgb"): env.render()
        self._own_dir = work_dir is None
        self.work_dir = Path(tempfile.mkdtemp(prefix="flowrun-")) if work_dir is None else work_dir
        self.k = self._make_kernel(network)
        self.controls: list[GroupControl] = build_controllers(network.vehicles)
        bind_per_vehicle_groups(self.controls, network.vehicles)  # Flow-style get_accel(env)
        self._flow_style = FlowStyleDriver(network.vehicles)
        self.k.group_routers = GroupRouters.of(network.vehicles)  # e.g. MinicityRouter
        self._init_bookkeeping()

    def _init_bookkeeping(self) -> None:
        """The counters, caches and RL-car queues of an episode, before the first reset."""
        self.step_counter = 0
        self.time_counter = 0
        self.record_frames = False
        self.read_xy = False
        self.collect_stats = False
        #: this episode's simulation steps not yet taken by ``Experiment`` (when it collects)
        self.records: list[StepRecord] = []
        self.reward_terms: dict[str, float] = {}
        self._ctrl_rng = np.random.default_rng(0)
        self._needs_reset = True
        self._closed = False
        self._space_cache: tuple[gymnasium.Space[Any], gymnasium.Space[Any]] | None = None
        #: the observation space's dtype and shape if it is a Box, else ``()``
        self._obs_box: tuple[Any, ...] | None = None
        self._painter: EnvPainter | None = None
        self._placement: RingPlacement | None = None
        self._clipper: ActionClipper | None = None
        #: RL cars waiting for a controlled place (Flow's ``rl_queue``) and the controlled
        #: ones in arrival order (Flow's ``rl_veh``); see :meth:`update_rl_queue`
        self.rl_queue: deque[str] = deque()
        self.rl_veh: list[str] = []
        self._queue_key: tuple[Any, int] | None = None

    def _make_kernel(self, network: Network) -> Kernel:
        """The kernel of this env (SUMO starts at the first reset), with the network's."""
        from flowrun.kernel import Kernel
        from flowrun.kernel.network import NetworkKernel
        from flowrun.kernel.sumo import gui_available

        gui = self.sim_params.render is True and gui_available()
        if self.sim_params.render is True and not gui:
            log.warning("render=True but no display or sumo-gui here: running headless")
        kernel = Kernel(self.sim_params, self.work_dir, gui=gui)
        kernel.network = NetworkKernel(network.spec, network=network)  # Flow: before reset
        # Flow's lights exist from the env's construction: set_state before reset waits
        kernel.traffic_light.expect([n.id for n in network.spec.nodes if n.type == "traffic_light"])
        return kernel

    # ------------------------------------------------------------------ Flow's hooks
    @property
    @abstractmethod
    def action_space(self) -> gymnasium.Space[Any]:  # type: ignore[override]
        """The agent's action space (subclasses implement)."""

    @property
    @abstractmethod
    def observation_space(self) -> gymnasium.Space[Any]:  # type: ignore[override]
        """The observation space (subclasses implement)."""

    @abstractmethod
    def _apply_rl_actions(self, rl_actions: Any) -> None:
        """Turn the agent's action into commands (subclasses implement)."""

    @abstractmethod
    def get_state(self) -> Any:
        """The observation (subclasses implement)."""

    def compute_reward(self, rl_actions: Any, **kwargs: Any) -> float:
        """The reward of the last step (subclasses implement)."""
        return 0.0

    def additional_command(self) -> None:
        """Anything to do every simulation step besides RL actions (optional)."""

    def update_rl_queue(self, places: int | None = None) -> None:
        """Keep :attr:`rl_veh` (at most ``places`` RL cars, first come first served) and
        :attr:`rl_queue` current as RL cars enter and leave the network.

        Cars that left are dropped, cars that entered are queued, and queued cars take free
        places in arrival order. Cheap to call often: nothing is done unless the population
        changed since the last call.
        """
        vk = self.k.vehicle
        key = (vk.table, vk.table.version)
        if key == self._queue_key:
            return
        self._queue_key = key
        rl_now = vk.get_rl_ids()
        present = set(rl_now)
        self.rl_veh = [v for v in self.rl_veh if v in present]
        self.rl_queue = deque(v for v in self.rl_queue if v in present)
        known = set(self.rl_veh).union(self.rl_queue)
        self.rl_queue.extend(v for v in rl_now if v not in known)
        limit = len(present) if places is None else places
        while self.rl_queue and len(self.rl_veh) < limit:
            self.rl_veh.append(self.rl_queue.popleft())

    def episode_network(self) -> Network:
        """The network of the next episode (override to vary it, e.g. the ring length)."""
        return self.network

    # ------------------------------------------------------------------ Gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Restart the simulation in the initial configuration and run the warm-up."""
        if seed is None and self._np_random is None:
            seed = int(self.sim_params.seed or 0)
        super().reset(seed=seed)
        if self._painter is not None:
            self._painter.reset()
        self.network = self.episode_network()
        self.scenario = self.network
        self.rl_queue.clear()
        self.rl_veh = []
        self._queue_key = None
        start = self.network.start_positions(self.np_random)
        table = build_table(
            self.network.vehicles, self.controls, start, self.network.spec, self.np_random
        )
        sumo_seed = int(self.np_random.integers(2**31 - 1))
        self._ctrl_rng = np.random.default_rng(int(self.np_random.integers(2**63 - 1)))
        route_rng = np.random.default_rng(int(self.np_random.integers(2**63 - 1)))
        self.k.sim_params = replace(self.sim_params, seed=sumo_seed)
        # Recording on a ring: edges, lane positions, x/y (from the lane shapes, not a getter
        # per car and step) and realised accelerations of the logged frames are derived for
        # a whole batch of steps at once (take_records).
        from flowrun.kernel.ring_reader import ring_fast_path

        closed = ring_fast_path(self.network.spec, table)
        self.k.reset(
            self.network,
            table,
            read_xy=self.read_xy or (self.record_frames and not closed),
            rng=route_rng,
        )
        self.k.vehicle.controllers = FlowControllers(
            self.network.vehicles, self.controls, self._flow_style
        )
        deferred = self.record_frames and closed and not self.read_xy
        self._placement = self.k.vehicle.placement() if deferred else None
        for control in self.controls:
            control.version = -1
            control.index = np.zeros(0, dtype=np.int64)
            control.controller.reset(0)
        self._flow_style.clear()
        self.step_counter = 0
        self.time_counter = 0
        self.records = []
        self._needs_reset = False
        self._emit_frame()
        for _ in range(self.env_params.warmup_steps):
            self._simulate(None)
            if self.k.simulation.check_collision():
                break
        self.step_counter = 0
        obs = self._format_obs(self.get_state())
        return obs, self._info(crash=False)

    def step(self, rl_actions: Any = None) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Apply the action (Flow's keyword ``rl_actions``) for ``sims_per_step`` steps."""
        action = rl_actions
        if self._needs_reset:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        if not self.k.started:
            self._needs_reset = True
            raise gymnasium.error.ResetNeeded(
                "this environment's SUMO simulation was stopped because another environment "
                "started one in this process (libsumo runs one per process); call reset(), "
                "or run each environment in its own subprocess"
            )
        # Flow rewards the action as applied: clipped to the action space when clip_actions.
        action = None if action is None else self.clip_actions(action)
        crash = False
        first = len(self.records)
        for _ in range(self.env_params.sims_per_step):
            self._simulate(action)
            crash = self.k.simulation.check_collision()
            if crash:
                break
        self.step_counter += 1
        obs = self._format_obs(self.get_state())
        reward = float(self.compute_reward(action, fail=crash))
        records = self.records
        for i in range(first, len(records)):  # this step's simulation steps get its reward
            records[i].reward = reward
        terminated = bool(crash)
        truncated = self.step_counter >= self.env_params.horizon
        if terminated or truncated:
            self._needs_reset = True
        return obs, reward, terminated, truncated, self._info(crash)

    def _simulate(self, action: Any) -> None:
        """One simulation step: human controllers, RL actions, extra commands, SUMO step."""
        self.time_counter += 1
        t = self.k.simulation.time
        vk = self.k.vehicle
        for gi, control in enumerate(self.controls):
            c = control.controller
            if c.is_rl or not c.commands_sumo:
                continue
            control.follow(vk.table, gi)
            if control.index.size == 0:
                continue
            if isinstance(c, PerVehicleGroup):  # Flow-style: one object per vehicle
                accel = c.actions(self, [vk.table.ids[i] for i in control.index])
            else:
                accel = c.get_accel(vk.inputs(control.sl, t), self._ctrl_rng)
            vk.apply_acceleration_idx(control.sl, accel)
        if self._flow_style:  # Flow-style lane-change and routing controllers, Flow's order
            self._flow_style.step(self)
        if action is not None:  # already clipped by ``step``
            self._apply_rl_actions(action)
        self.additional_command()
        if self.sim_params.render:  # Flow colours cars only when someone watches
            self.k.vehicle.update_vehicle_colors()
        self.k.step()
        self._emit_frame()

    @property
    def available_routes(self) -> dict[str, list[tuple[list[str], float]]]:
        """Flow's ``env.available_routes``: ``k.network.rts``, for routing controllers."""
        return self.k.network.rts

    @property
    def controller_rng(self) -> np.random.Generator:
        """Generator of the controllers' noise (drawn afresh from the seed at every reset)."""
        return self._ctrl_rng

    def apply_rl_actions(self, rl_actions: Any = None) -> None:
        """Clip (if asked) and apply the agent's action; ``None`` does nothing."""
        if rl_actions is None:
            return
        self._apply_rl_actions(self.clip_actions(rl_actions))

    def _spaces(self) -> tuple[gymnasium.Space[Any], gymnasium.Space[Any]]:
        # Subclasses build spaces in properties (Flow's style); they depend only on the
        # initial vehicles, so build them once instead of on every step.
        if self._space_cache is None:
            self._space_cache = (self.action_space, self.observation_space)
        return self._space_cache

    def clip_actions(self, rl_actions: Any) -> Any:
        """Clip a Box action (or each Box part of a Tuple action) to the action space when
        ``env_params.clip_actions``."""
        if self._clipper is None:
            self._clipper = ActionClipper(self.env_params.clip_actions)
        return self._clipper.clip(self._spaces()[0], rl_actions)

    def _format_obs(self, obs: Any) -> Any:
        box = self._obs_box
        if box is None:  # (the spaces are made once: their dtype and shape, kept)
            space = self._spaces()[1]
            box = self._obs_box = (
                (space.dtype, space.shape) if isinstance(space, gymnasium.spaces.Box) else ()
            )
        if box:
            obs = np.asarray(obs, dtype=box[0])
            return obs if obs.shape == box[1] else obs.reshape(box[1])
        return obs

    def _info(self, crash: bool) -> dict[str, Any]:
        speed = self.k.vehicle.speed
        return {
            "crash": crash,
            "mean_speed": float(np.add.reduce(speed)) / speed.size if speed.size else 0.0,
            "collisions": self.k.simulation.collisions,
            "teleports": self.k.simulation.teleports,
            "time": self.k.simulation.time,
            "reward_terms": dict(self.reward_terms),
        }

    def terminate(self) -> None:
        """Flow's name for :meth:`close`."""
        self.close()

    def close(self) -> None:
        """Stop SUMO and remove the private work folder (safe to call twice)."""
        if self._closed:
            return
        self._closed = True
        self.k.close()
        if self._own_dir:
            shutil.rmtree(self.work_dir, ignore_errors=True)

    def __del__(self) -> None:
        with contextlib.suppress(Exception):  # interpreter shutdown
            self.close()

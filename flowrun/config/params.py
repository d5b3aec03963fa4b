"""Flow's parameter objects, as typed data. The YAML config is made of exactly these.

Each class mirrors the Flow class of the same name (same field names and defaults, except where
a default is documented as deliberately different). ``YAML_KEYS`` maps a YAML key to a field
name where the config uses a shorter spelling (``sim.step`` -> ``SumoParams.sim_step``).
They are plain mutable dataclasses, as Flow's objects are (Flow code sets
``sim_params.render = True``); the loader checks every value when a config is read
(:mod:`flowrun.config.checks`), and :func:`flowrun.config.validate.check_params` checks
objects built in Python. The vehicle-type classes live in :mod:`flowrun.config.vtype` and
:mod:`flowrun.config.vehicles` and are re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from flowrun.config.compat import no_internal_links, removed_keywords
from flowrun.config.inflows import InFlow as InFlow
from flowrun.config.inflows import InFlows as InFlows
from flowrun.config.modes import LANE_CHANGE_MODES as LANE_CHANGE_MODES
from flowrun.config.modes import SPEED_MODES as SPEED_MODES
from flowrun.config.traffic_lights import TrafficLightParams as TrafficLightParams
from flowrun.config.vehicles import ControllerArg as ControllerArg
from flowrun.config.vehicles import ControllerSpec as ControllerSpec
from flowrun.config.vehicles import VehicleParams as VehicleParams
from flowrun.config.vehicles import VehicleType as VehicleType
from flowrun.config.vehicles import controller_spec as controller_spec
from flowrun.config.vehicles import is_rl as is_rl
from flowrun.config.vtype import SumoCarFollowingParams as SumoCarFollowingParams
from flowrun.config.vtype import SumoLaneChangeParams as SumoLaneChangeParams
from flowrun.config.vtype import vtype_attributes as vtype_attributes


@dataclass
class SumoParams:
    """Simulation settings (Flow's ``SumoParams``, Flow's field names and defaults).

    Mutable, as in Flow (``sim_params.render = True``); values are checked when a config is
    loaded or a ``flow_params`` dict is read.

    Attributes:
        sim_step: seconds per simulation step (YAML key ``step``).
        seed: seed of every random draw (SUMO's and flowrun's); ``None`` means 0.
        render: ``True`` opens ``sumo-gui`` through TraCI. Without a display flowrun warns and
            runs headless instead, so scripts written for a desktop still run on a server.
            Flow's pyglet modes ``"rgb"``, ``"drgb"``, ``"gray"`` and ``"dgray"`` (one frame
            per step for visualisation or a pixel observation) run headless and make the env
            draw frames with flowrun's painter: ``env.render()`` returns the current frame
            (``render_mode="rgb_array"`` is implied), grey for the gray modes.
        teleport_time: SUMO ``--time-to-teleport``; -1 disables teleporting of stuck cars.
        use_ballistic: ballistic position update instead of SUMO's default Euler update.
        lateral_resolution: SUMO's sublane model resolution in metres; ``None`` disables it.
        emission_path: folder for ``Experiment.run(convert_to_csv=True)`` outputs (Flow's
            emission CSV); flowrun's own logs are MCAP files in the run folder.
        print_warnings: show SUMO's own warnings. flowrun's default is ``False`` (Flow's
            ``True``): SUMO's warnings would interleave with the progress bar.
        restart_instance: stored for Flow compatibility (flowrun always restarts cheaply).
        port: TraCI port (Flow's). Stored, not used: libsumo runs in-process.
        no_step_log: Flow's switch for SUMO's step log; flowrun always passes
            ``--no-step-log``. Stored.
        overtake_right: allow overtaking on the right (SUMO
            ``--lanechange.overtake-right``). Stored for the kernel's command line.
        num_clients: TraCI clients (Flow's). Stored, not used.
        use_libsumo: Flow's switch from TraCI to libsumo. Stored, not used: flowrun always
            runs libsumo (sumo-gui over TraCI when rendering).
        save_render, sight_radius, show_radius, pxpm: Flow's pyglet renderer settings
            (save frames, RL observation radius in m, draw it, pixels per metre). Stored
            only: flowrun has no pyglet renderer.
        force_color_update, color_by_speed: Flow's sumo-gui colouring switches. Stored only.
        disable_collisions: later Flow's switch for SUMO's collision checks. Stored only
            (flowrun always counts collisions).
        backend: ``sumo`` (default: SUMO through libsumo) or ``numpy`` (flowrun's vectorised
            single-lane ring, many rings stepped at once; flowrun's addition).
    """

    YAML_KEYS: ClassVar[dict[str, str]] = {"step": "sim_step"}

    sim_step: float = 0.1
    seed: int | None = None
    render: bool | str = False
    teleport_time: float = -1.0
    use_ballistic: bool = False
    lateral_resolution: float | None = None
    emission_path: str | None = None
    print_warnings: bool = False
    restart_instance: bool = False
    port: int | None = None
    no_step_log: bool = True
    overtake_right: bool = False
    num_clients: int = 1
    use_libsumo: bool = False
    save_render: bool = False
    sight_radius: float = 25.0
    show_radius: bool = False
    pxpm: float = 2.0
    force_color_update: bool = False
    color_by_speed: bool = False
    disable_collisions: bool = False
    backend: str = "sumo"


@dataclass
class EnvParams:
    """Environment settings (Flow's ``EnvParams``). Mutable, as in Flow
    (``flow_params["env"].horizon = 1000``).

    Attributes:
        additional_params: the environment's own parameters (its ``ADDITIONAL_ENV_PARAMS``).
        horizon: RL steps per episode; the episode is *truncated* after it.
        warmup_steps: steps run with no RL action at each reset before the episode starts.
        sims_per_step: simulation steps per RL step (actions held constant).
        evaluate: Flow's flag for evaluation-mode rewards.
        clip_actions: clip RL actions to the action space.
        env_class: name of a built-in environment or ``package.module:Class`` (YAML key
            ``class``). ``None`` means ``AccelEnv``. flowrun's addition (Flow names the env
            in ``flow_params["env_name"]``).
        done_at_exit: later Flow's flag (multi-agent envs: an agent is done when its car
            leaves the network). Stored; flowrun's single-agent envs do not use it.
    """

    YAML_KEYS: ClassVar[dict[str, str]] = {"class": "env_class"}

    additional_params: dict[str, Any] = field(default_factory=dict)
    horizon: float = math.inf
    warmup_steps: int = 0
    sims_per_step: int = 1
    evaluate: bool = False
    clip_actions: bool = True
    env_class: str | None = None
    done_at_exit: bool = True

    def get_additional_param(self, key: str) -> Any:
        """``additional_params[key]`` (Flow's accessor)."""
        return self.additional_params[key]


@removed_keywords({"no_internal_links": no_internal_links})
@dataclass
class NetParams:
    """Network parameters (Flow's ``NetParams``). Mutable, as in Flow
    (``net_params.additional_params["length"] = 260``).

    Attributes:
        additional_params: the network type's parameters (its ``ADDITIONAL_NET_PARAMS``).
        inflows: vehicles entering the network; ``None`` means none (an empty
            :class:`InFlows`, as Flow's default).
        template: a SUMO ``.net.xml`` path, or Flow's dict ``{"net": ..., "rou": [...],
            "vtype": [...]}``, for a network read from files.
        osm_path: an OpenStreetMap file to import with netconvert.

    Flow's 2019 keyword ``no_internal_links`` is accepted when false, with a deprecation
    warning (junction-internal links are always built where roads meet, as Flow does since),
    and refused when true; see :func:`flowrun.config.compat.no_internal_links`.
    """

    additional_params: dict[str, Any] = field(default_factory=dict)
    inflows: InFlows | None = None
    template: str | dict[str, Any] | None = None
    osm_path: str | None = None

    def __post_init__(self) -> None:
        if self.inflows is None:
            self.inflows = InFlows()


@dataclass
class InitialConfig:
    """Initial placement of the vehicles (Flow's ``InitialConfig``). Mutable, as in Flow
    (``initial_config.spacing = "custom"``).

    Attributes:
        shuffle: shuffle the order of vehicle types along the road (seeded).
        spacing: ``uniform`` (evenly spaced), ``random`` (uniformly random gaps) or
            ``custom`` (the network's own ``gen_custom_start_pos``).
        min_gap: extra bumper-to-bumper gap kept between cars when placing them, metres.
        perturbation: std of a Gaussian offset added to each uniform position, metres.
        x0: position of the first car along the network, metres.
        bunching: metres of road left empty; cars fill ``length - bunching`` (a negative
            value counts as 0, as in Flow).
        lanes_distribution: how many lanes cars are spread over (``inf`` = all lanes).
        edges_distribution: ``all``, a list of edge names to place cars on, or Flow's dict
            of edge name -> number of cars.
        additional_params: network-specific placement data (``custom`` spacing reads it).
    """

    shuffle: bool = False
    spacing: str = "uniform"
    min_gap: float = 0.0
    perturbation: float = 0.0
    x0: float = 0.0
    bunching: float = 0.0
    lanes_distribution: float = math.inf
    edges_distribution: str | list[str] | dict[str, int] = "all"
    additional_params: dict[str, Any] = field(default_factory=dict)

    def get_additional_params(self, key: str) -> Any:
        """``additional_params[key]`` (Flow's accessor)."""
        return self.additional_params[key]

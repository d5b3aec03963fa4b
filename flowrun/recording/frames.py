"""What one logged step holds: column arrays for every vehicle, plus per-step aggregates.

The kernel fills a :class:`VehicleFrame` from its per-step snapshot; the recorder writes it to
``/flowrun/vehicles`` and a :class:`StepStats` to ``/flowrun/stats`` (and, on networks with
traffic lights, a :class:`SignalFrame` to ``/flowrun/traffic_lights``). Readers return the same
types, so a log read back compares equal field by field with what the simulation reported.
"""

from __future__ import annotations

from dataclasses import dataclass

from flowrun.types import BoolArray, FloatArray, IntArray


@dataclass(slots=True)
class VehicleFrame:
    """All vehicles at one logged step (each array/list has one entry per vehicle).

    Treat as read-only: the kernel hands over its own arrays and lists, and the recorder
    reuses the encoding of a column it has seen before (the same object is not re-read), so
    build a new frame (``dataclasses.replace``) with new columns instead of changing one.
    Not frozen only because a frozen dataclass's ``__init__`` costs ~1.5 µs more per step.

    Attributes:
        step: simulation step index since the episode started (warm-up included).
        time: simulation time, s.
        ids: vehicle ids.
        types: vehicle group names (``idm``, ``rl``, ...).
        edges: SUMO edge id each vehicle is on.
        lanes: lane index.
        lane_pos: position along the lane, m.
        position: position along the network (ring position for rings), m.
        odometer: distance travelled since the episode started, m.
        x: x coordinate, m.
        y: y coordinate, m.
        speed: speed, m/s.
        accel_cmd: commanded acceleration, m/s^2 (``nan`` where SUMO drove the car).
        accel_real: realised acceleration over the last step, m/s^2.
        headway: bumper-to-bumper gap to the leader, m (``inf`` when none).
        leader: leader id (``""`` when none).
        is_rl: whether the RL agent drives the vehicle.
    """

    step: int
    time: float
    ids: list[str]
    types: list[str]
    edges: list[str]
    lanes: IntArray
    lane_pos: FloatArray
    position: FloatArray
    odometer: FloatArray
    x: FloatArray
    y: FloatArray
    speed: FloatArray
    accel_cmd: FloatArray
    accel_real: FloatArray
    headway: FloatArray
    leader: list[str]
    is_rl: BoolArray


@dataclass(slots=True)
class StepStats:
    """Aggregates of one logged step (treat as read-only, like :class:`VehicleFrame`; the one
    exception: ``Env.step`` fills in ``reward`` of the steps it queued before anyone reads them).

    Attributes:
        step: simulation step index.
        time: simulation time, s.
        num_vehicles: vehicles in the network.
        mean_speed: mean speed, m/s.
        min_speed: minimum speed, m/s.
        max_speed: maximum speed, m/s.
        speed_std: standard deviation of speed across vehicles, m/s.
        reward: reward of the RL step this simulation step belongs to (``nan`` if none).
        collisions: collisions SUMO reported in this step.
        teleports: teleports SUMO started in this step.
        departed: vehicles that entered the network since the previous logged step (this
            step's own when every step is logged; 0 in logs written before flowrun logged it).
        arrived: vehicles that left the network (end of route, or removed) since the previous
            logged step.
        lane_changes: cars that changed lane (same edge, another lane) since the previous
            logged step (0 on single-lane networks and in logs written before it was logged).
    """

    step: int
    time: float
    num_vehicles: int
    mean_speed: float
    min_speed: float
    max_speed: float
    speed_std: float
    reward: float
    collisions: int
    teleports: int
    departed: int = 0
    arrived: int = 0
    lane_changes: int = 0


@dataclass(slots=True)
class SignalFrame:
    """Every traffic light at one logged step (``/flowrun/traffic_lights``), one entry per
    light in each list/array. Treat as read-only, like :class:`VehicleFrame`.

    Attributes:
        step: simulation step index (the vehicle frame of the same step has the same one).
        time: simulation time, s.
        ids: traffic light ids (their junctions' ids).
        states: SUMO state strings, one character per controlled link (``G``, ``y``, ``r``...).
        phases: index of the running phase in the light's program.
        programs: id of the running program (``online`` once a controller set a state).
    """

    step: int
    time: float
    ids: list[str]
    states: list[str]
    phases: IntArray
    programs: list[str]

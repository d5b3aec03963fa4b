"""``RingBatch``: B single-lane rings of one config, stepped together with numpy.

Each ring keeps the random streams the SUMO backend's env would have after the same seed:
its own episode generator (gymnasium's ``np_random``: ring length, placement, seeds) and its
own controller-noise generator, whose draws are taken in the same order (group by group,
step by step). Draws are made in blocks of :data:`NOISE_BLOCK` steps per ring, which gives
the same numbers as drawing step by step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium.utils import seeding

from flowrun.fastring.physics import (
    NUMERICAL_EPS,
    commanded_speed,
    flat_index,
    noise_term,
    ring_order,
    sumo_driven_speed,
    sumo_idm_follow_speed,
)
from flowrun.fastring.plan import RingPlan
from flowrun.networks.base import Network
from flowrun.networks.ring import ring_edge_count
from flowrun.types import BoolArray, CarFollowingInputs, FloatArray, IntArray

#: simulation steps of controller noise drawn at once per ring
NOISE_BLOCK = 128


@dataclass
class RingState:
    """The moving state of ``B`` rings (arrays ``(N, B)`` unless noted).

    Attributes:
        start: entry position of every car, m. odo: distance driven, m. speed: m/s.
        leader, follower: row of each car's leader / follower on its ring.
        offset: headway offset (see :func:`~flowrun.fastring.physics.ring_order`), m.
        headway: bumper-to-bumper gap to the leader now, m.
        length: ring lengths, m, ``(B,)``.
        steps: simulation steps since the episode started, ``(B,)``.
    """

    start: FloatArray
    odo: FloatArray
    speed: FloatArray
    leader: IntArray
    follower: IntArray
    offset: FloatArray
    headway: FloatArray
    length: FloatArray
    steps: IntArray

    def __post_init__(self) -> None:
        self.index()

    def index(self) -> None:
        """Refresh the leader/follower indices (after the columns changed).

        When every ring has the same cyclic order (the usual case: cars placed in id order)
        a gather is a copy of whole rows, much cheaper than an element-wise ``take``.
        """
        self.u = self.start + self.odo
        first = self.leader[:, :1]
        if self.leader.size and bool((self.leader == first).all()):
            self.shared: tuple[IntArray, IntArray] | None = (
                self.leader[:, 0].copy(),
                self.follower[:, 0].copy(),
            )
        else:
            self.shared = None
            self.lead_flat = flat_index(self.leader)
            self.follow_flat = flat_index(self.follower)

    def of_leader(self, x: FloatArray) -> FloatArray:
        """``x`` (``(N, B)``) of every car's leader."""
        if self.shared is not None:
            return x[self.shared[0]]
        return np.take(x, self.lead_flat)

    def of_follower(self, x: FloatArray) -> FloatArray:
        """``x`` (``(N, B)``) of every car's follower."""
        if self.shared is not None:
            return x[self.shared[1]]
        return np.take(x, self.follow_flat)

    @property
    def position(self) -> FloatArray:
        """Ring position of every car, m (``get_x_by_id``): ``(start + odo) mod length``."""
        return np.mod(self.u, self.length)

    def take(self, cols: IntArray) -> RingState:
        """The rings ``cols`` as a state of their own (copies)."""
        return RingState(
            self.start[:, cols], self.odo[:, cols], self.speed[:, cols], self.leader[:, cols],
            self.follower[:, cols], self.offset[:, cols], self.headway[:, cols],
            self.length[cols], self.steps[cols],
        )  # fmt: skip

    def put(self, cols: IntArray, part: RingState) -> None:
        """Write ``part`` (a state of ``len(cols)`` rings) into the rings ``cols``."""
        for name in ("start", "odo", "speed", "leader", "follower", "offset", "headway"):
            getattr(self, name)[:, cols] = getattr(part, name)
        self.length[cols] = part.length
        self.steps[cols] = part.steps
        self.index()


class NoiseStreams:
    """Each ring's controller-noise generator, drawn ahead in blocks (standard normals).

    Ring ``j``'s block is ``buf[j]`` (``NOISE_BLOCK`` steps x ``M`` draws, contiguous) and
    ``cursor[j]`` the step it is at; a spent block is refilled from the ring's generator.
    """

    def __init__(self, num_draws: int, num_rings: int) -> None:
        self.m = num_draws
        self.b = num_rings
        self.gens: list[np.random.Generator | None] = [None] * num_rings
        self.buf = np.zeros((num_rings, NOISE_BLOCK, num_draws))
        self.cursor = np.full(num_rings, NOISE_BLOCK, dtype=np.int64)
        self._base = np.arange(num_draws)[:, None] + np.arange(num_rings) * (
            NOISE_BLOCK * num_draws
        )

    def restart(self, col: int, seed: int) -> None:
        """Ring ``col`` starts a new episode with a generator seeded ``seed``."""
        self.gens[col] = np.random.default_rng(seed)
        self.cursor[col] = NOISE_BLOCK

    def _refill(self, cols: IntArray) -> None:
        for j in cols.tolist():
            gen = self.gens[j]
            assert gen is not None, "restart() a ring before drawing its noise"
            gen.standard_normal((NOISE_BLOCK, self.m), out=self.buf[j])
            self.cursor[j] = 0

    def draw(self, cols: IntArray | None = None) -> FloatArray:
        """One step of standard normals for the rings ``cols`` (all by default), ``(M, b)``."""
        if self.m == 0:
            n = self.b if cols is None else cols.size
            return np.zeros((0, n))
        if cols is None:
            if self.cursor.max() >= NOISE_BLOCK:
                self._refill(np.flatnonzero(self.cursor >= NOISE_BLOCK))
            z = np.take(self.buf, self._base + self.cursor * self.m)
            self.cursor += 1
            return z
        cur = self.cursor[cols]
        if cur.max() >= NOISE_BLOCK:
            self._refill(cols[cur >= NOISE_BLOCK])
            cur = self.cursor[cols]
        z = np.take(self.buf, self._base[:, cols] + cur * self.m)
        self.cursor[cols] += 1
        return z


class RingPhysics:
    """One simulation step of a :class:`RingState` under a :class:`RingPlan` (no randomness
    of its own: noise comes in as standard normals)."""

    def __init__(self, plan: RingPlan) -> None:
        self.plan = plan
        self._cache: dict[int, list[tuple[FloatArray, FloatArray, FloatArray, FloatArray]]] = {}
        self.rl = plan.rl_rows
        self.humans = [g for g in plan.groups if not g.is_rl]
        #: keep each step's commanded accelerations in :attr:`last_accel` (for logs)
        self.keep_accel = False
        self.last_accel: FloatArray | None = None
        capped = plan.safe_cap.copy()
        capped[self.rl] = False
        self.capped_humans = np.flatnonzero(capped)
        rl = self.rl
        contiguous = rl.size and int(rl[-1]) - int(rl[0]) + 1 == rl.size
        #: the RL rows as a slice when contiguous (a view instead of a gather)
        self.rl_rows: slice | IntArray = slice(int(rl[0]), int(rl[-1]) + 1) if contiguous else rl
        self.rl_all_capped = bool(plan.safe_cap[rl].all()) if rl.size else False
        self._rl_params = self._column_params(rl)

    def _column_params(self, rows: IntArray) -> dict[str, FloatArray]:
        """The vehicle-type facts of the cars ``rows`` as columns ``(len(rows), 1)``."""
        p = self.plan
        return {
            name: getattr(p, name)[rows][:, None]
            for name in ("des_speed", "accel", "decel", "tau", "min_gap", "emergency_decel",
                         "max_speed")
        }  # fmt: skip

    def _limits(self, b: int) -> list[tuple[FloatArray, FloatArray, FloatArray, FloatArray]]:
        """Per human group: max accel, max decel, lengths and speed limits, for ``b`` rings."""
        if b not in self._cache:
            p = self.plan
            self._cache[b] = [
                (np.repeat(p.accel[g.start : g.stop], b), np.repeat(p.decel[g.start : g.stop], b),
                 np.repeat(p.lengths[g.start : g.stop], b),
                 np.full((g.stop - g.start) * b, p.speed_limit))
                for g in self.humans
            ]  # fmt: skip
        return self._cache[b]

    def _accel_rows(self, b: int) -> FloatArray:
        if self.last_accel is None or self.last_accel.shape[1] != b:
            self.last_accel = np.full((self.plan.num_cars, b), np.nan)
        return self.last_accel

    def safe_speed(
        self,
        s: RingState,
        rows: IntArray | slice,
        leader_speed: FloatArray,
        params: dict[str, FloatArray] | None = None,
    ) -> FloatArray:
        """SUMO's IDM follow speed of the cars ``rows`` (``(len(rows), B)``), m/s."""
        if params is None:
            assert not isinstance(rows, slice)
            params = self._column_params(rows)
        c = params
        return sumo_idm_follow_speed(
            s.speed[rows], s.headway[rows], leader_speed[rows],
            des_speed=c["des_speed"], accel=c["accel"], decel=c["decel"], tau=c["tau"],
            min_gap=c["min_gap"], dt=self.plan.dt,
        )  # fmt: skip

    def step(self, s: RingState, z: FloatArray, rl_accel: FloatArray | None) -> BoolArray:
        """Advance every ring one step; returns which rings SUMO would report a collision on.

        Args:
            s: the rings (updated in place).
            z: standard normals of this step, ``(M, B)`` (see :class:`NoiseStreams`).
            rl_accel: accelerations of the RL cars, ``(num_rl, B)``; ``None``: SUMO drives them.
        """
        dt = self.plan.dt
        b = s.length.size
        vl = s.of_leader(s.speed)
        nxt = self._human_speeds(s, z, vl, b)
        if self.rl.size:
            self._rl_speeds(s, rl_accel, vl, nxt, b)
        s.speed = nxt
        s.odo = s.odo + nxt * dt
        u = s.u = s.start + s.odo
        headway = s.of_leader(u)
        headway -= u
        headway += s.offset
        s.headway = headway
        s.steps = s.steps + 1
        if headway.min() >= -NUMERICAL_EPS:
            return np.zeros(b, dtype=bool)
        return reported_collisions(s, headway < -NUMERICAL_EPS)

    def _human_speeds(self, s: RingState, z: FloatArray, vl: FloatArray, b: int) -> FloatArray:
        """Every car's next speed, m/s, ``(N, B)``: the human cars' from their controllers
        (noise from ``z``, capped by SUMO's safe speed where their speed mode says so); the
        RL cars' rows are left for :meth:`_rl_speeds`. ``vl``: every car's leader's speed."""
        p = self.plan
        dt, limit = p.dt, p.speed_limit
        v = s.speed
        fh = s.of_follower(s.headway)
        fv = s.of_follower(v)
        nxt = np.empty_like(v)
        limits = self._limits(b)
        k = 0
        time = float(s.steps[0] + 2) * dt if b else 0.0  # SUMO's clock (start + insertion steps)
        for g, (max_accel, max_decel, length, speed_limit) in zip(self.humans, limits, strict=True):
            sl = slice(g.start, g.stop)
            n = g.stop - g.start
            inputs = CarFollowingInputs(
                v[sl].reshape(-1), s.headway[sl].reshape(-1), vl[sl].reshape(-1),
                fh[sl].reshape(-1), fv[sl].reshape(-1), speed_limit, dt, time,
                max_accel, max_decel, length,
            )  # fmt: skip
            acc = np.asarray(g.controller._accel(inputs), dtype=np.float64).reshape(n, b)
            if g.controller.noise > 0:
                acc = acc + noise_term(dt, g.controller.noise, z[k : k + n])
                k += n
            nxt[sl] = commanded_speed(v[sl], acc, dt, limit)
            if self.keep_accel:
                self._accel_rows(b)[sl] = acc
        if self.capped_humans.size:
            rows = self.capped_humans
            nxt[rows] = np.minimum(nxt[rows], self.safe_speed(s, rows, vl))
        return nxt

    def _rl_speeds(
        self, s: RingState, rl_accel: FloatArray | None, vl: FloatArray, nxt: FloatArray, b: int
    ) -> None:
        """The RL cars' next speeds into ``nxt``: SUMO's own driving without commands, else
        the commanded accelerations, capped by the safe speed where the speed mode says so."""
        p = self.plan
        dt, limit = p.dt, p.speed_limit
        v, rl, c = s.speed, self.rl_rows, self._rl_params
        v_safe = self.safe_speed(s, rl, vl, c)
        if rl_accel is None:
            nxt[rl] = sumo_driven_speed(
                v[rl], v_safe, accel=c["accel"], decel=c["decel"],
                emergency_decel=c["emergency_decel"], max_speed=c["max_speed"],
                lane_max=c["des_speed"], dt=dt,
            )  # fmt: skip
        elif self.rl_all_capped:
            nxt[rl] = np.minimum(commanded_speed(v[rl], rl_accel, dt, limit), v_safe)
        else:
            target = commanded_speed(v[rl], rl_accel, dt, limit)
            cap = p.safe_cap[self.rl][:, None]
            nxt[rl] = np.where(cap, np.minimum(target, v_safe), target)
        if self.keep_accel:
            self._accel_rows(b)[rl] = np.nan if rl_accel is None else rl_accel


def reported_collisions(s: RingState, overlap: BoolArray) -> BoolArray:
    """Which rings SUMO reports a collision on, given which cars overlap their leader.

    SUMO checks each lane's consecutive vehicles (fronts on the same lane), and its rearmost
    vehicle against a leader whose back hangs over the lane's end: such an overlap across an
    edge boundary is seen only when the follower is the only car on its edge (measured on
    flowrun's ring, ``tests/test_fastring_sumo.py``).
    """
    n_edges = np.array([ring_edge_count(float(x)) for x in s.length])
    edge_len = s.length / n_edges
    edge = np.minimum(np.floor(np.mod(s.u, s.length) / edge_len), n_edges - 1).astype(np.int64)
    same = edge == s.of_leader(edge)
    cols = np.broadcast_to(np.arange(edge.shape[1]), edge.shape)
    count = np.zeros((int(n_edges.max()), edge.shape[1]), dtype=np.int64)
    np.add.at(count, (edge, cols), 1)
    alone = count[edge, cols] == 1
    return np.asarray((overlap & (same | alone)).any(axis=0))


@dataclass
class EpisodeStart:
    """What a ring's episode generator decides at a reset (as the SUMO env draws it)."""

    network: Network
    start: FloatArray
    speed: FloatArray
    noise_seed: int


def draw_episode(
    plan: RingPlan,
    rng: np.random.Generator,
    cache: dict[float, Network],
    length: float | None = None,
) -> EpisodeStart:
    """Ring length, placement and the controller-noise seed, drawn from ``rng`` in the SUMO
    env's order (``episode_network``, ``start_positions``, SUMO's seed, noise seed, routes).

    ``length`` (m) sets the ring's length as the SUMO env's ``reset(options={"ring_length":
    L})`` does: the length is still drawn first, so every other draw is the same.
    """
    network = plan.network
    drawn = None if plan.bounds is None else int(rng.integers(plan.bounds[0], plan.bounds[1] + 1))
    if length is None:
        length = drawn
    if length is not None:
        if length not in cache:
            cache[length] = plan.network.with_params(length=length)
        network = cache[length]
    placed = network.start_positions(rng)
    starts = network.spec.edge_starts
    start = np.array([starts[e] + lp for e, lp in zip(placed.edges, placed.lane_pos, strict=True)])
    rng.integers(2**31 - 1)  # SUMO's own seed: nothing random in SUMO on this ring
    noise_seed = int(rng.integers(2**63 - 1))
    rng.integers(2**63 - 1)  # route choices: one route per edge on the ring
    speed = np.array(
        [g.initial_speed for g in plan.cfg.vehicles.groups for _ in range(g.num_vehicles)],
        dtype=np.float64,
    )
    return EpisodeStart(network, start, speed, noise_seed)


def fresh_state(plan: RingPlan, episodes: list[EpisodeStart]) -> RingState:
    """The state at the start of the given episodes (one ring each, before the warm-up)."""
    start = np.stack([e.start for e in episodes], axis=1)
    length = np.array([e.network.spec.length for e in episodes], dtype=np.float64)
    speed = np.stack([e.speed for e in episodes], axis=1)
    leader, follower, offset = ring_order(start, plan.lengths, length)
    headway = np.take(start, flat_index(leader)) - start + offset
    b = len(episodes)
    return RingState(
        start, np.zeros_like(start), speed, leader, follower, offset, headway, length,
        np.zeros(b, dtype=np.int64),
    )  # fmt: skip


def new_generator(seed: int | None) -> np.random.Generator:
    """gymnasium's ``np_random`` for ``seed`` (as ``Env.reset(seed=...)`` makes it)."""
    rng, _ = seeding.np_random(seed)
    return rng

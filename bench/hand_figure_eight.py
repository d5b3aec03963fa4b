"""Hand-written AV rules on figureeight0 (``bench/hand_policies.py figureeight0``).

Every rule reads only what ``AccelEnv`` observes (each car's speed / max speed and position
``x`` / network length ``L``, in the env's car order, the AV last) and returns the AV's
acceleration (m/s^2; the env clips it to +-3). The two crossing links (``:center_1``,
``bottom -> top``, and ``:center_0``, ``right -> left``) start about half a loop apart, so
every car passes the one junction twice a lap, and a car heading for one link conflicts with
the cars heading for the other. No car overtakes on the one-lane loop, so the AV's leader is
always the same car: the last of the column that drives behind the AV.

* ``idm v*``: the humans' IDM (T 1 s, s0 2 m, a 1, b 1.5) with desired speed ``v*``, braking
  by the gap to the car ahead.
* ``+cross c``: the AV also treats the nearest car due at the junction before it on the
  other link as a leader, with the difference of their distances to the junction minus ``c``
  as the gap: it times its arrival at the crossing into the other stream's gaps.
* ``hold G, then ...``: the AV stands (-3 m/s^2) until its gap to the car ahead is ``G`` m,
  that is until the other 13 cars stand within ``L - G - 5`` m behind it (the column has
  formed); then it drives the rule after the comma.
* ``idm 30 s0 215 T 0``: IDM with a jam gap of 215 m and no time headway: the AV stands until
  its gap ahead is 215 m, then keeps the column behind it shorter than half the loop.
* ``gap-speed g0 tau``: ``a = (gap - g0) / tau - v`` (clipped to +-3), ``gap`` being the AV's
  gap to the car ahead: the AV steers its speed towards ``(gap - g0) / tau``, a linear function
  of its gap and speed. It stands while its leader is near, sets off as the leader drives away
  and the column behind the AV closes up, and cruises at the speed at which the gap is
  ``g0 + tau * v``, so that the column stays shorter than half the loop. ``+cross c``: the
  lower of this and ``idm 30 +cross c``. ``linear`` takes the gap as a linear function of the
  observation can: ``x_leader - x_AV - 5`` without the wrap-around modulo ``L``.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from flowrun.controllers.car_following_formulas import idm_accel

CAR = 5.0  #: vehicle length, m
#: a car has left the junction once its front is this far past its crossing link's start (the
#: 9.4 m link plus its length), m
CLEAR = 14.4
MID = 4.7  #: the crossing links' conflict point (where they cross): their middle, m past the start


@dataclass(frozen=True)
class Loop:
    """What a rule knows of the network: length, the crossing links' starts (x, m), the
    observation's speed scale, and which entry of the car order is the AV."""

    length: float
    crossings: tuple[float, float]
    max_speed: float
    av: int


def leader_gap(x: np.ndarray, i: int, length: float) -> tuple[float, int]:
    """Bumper-to-bumper gap (m) from car ``i`` to the next car ahead on the loop, and that car."""
    ahead = (x - x[i]) % length
    ahead[i] = np.inf
    j = int(np.argmin(ahead))
    return float(ahead[j]) - CAR, j


def to_junction(x: np.ndarray, crossing: float, length: float, clear: float) -> np.ndarray:
    """Distance (m) of each car to the start of ``crossing``'s link; negative for a car on it
    that has not cleared it yet (its front less than ``clear`` m past the start)."""
    past = (x - crossing) % length
    return np.where(past < clear, -past, (crossing - x) % length)


def crossing_gap(x: np.ndarray, i: int, loop: Loop, clear: float) -> tuple[float, int]:
    """Car ``i``'s gap to the junction's next conflicting car: the nearest car due at the
    junction before it on the other link (its distance to the junction minus the other's,
    minus ``clear``); ``inf`` when car ``i`` is on its link already or nobody is due."""
    length = loop.length
    to = [to_junction(x, c, length, clear) for c in loop.crossings]
    if to[0][i] < 0 or to[1][i] < 0:
        return math.inf, -1
    mine = 0 if to[0][i] < to[1][i] else 1
    d_i, other = to[mine][i], to[1 - mine]
    # a car heads for the other link when it is nearer that link's start than this one's
    heading = (other < to[mine]) | (other < 0)
    heading[i] = False
    due = np.flatnonzero(heading & (other <= d_i))
    if due.size == 0:
        return math.inf, -1
    j = int(due[np.argmax(other[due])])
    return float(d_i - other[j] - clear), j


def gap_speed_accel(gap: float, v: float, g0: float, tau: float, gain: float = 1.0) -> float:
    """``gap-speed``: ``gain`` (1/s) times the difference between the speed
    ``(gap - g0) / tau`` and ``v``, clipped to the action space."""
    return float(np.clip(gain * ((gap - g0) / tau - v), -3.0, 3.0))


def idm_equilibrium_speed(gap: float, v0: float = 30.0, s0: float = 2.0, t: float = 1.0) -> float:
    """The speed at which the humans' IDM (delta 4) keeps a steady ``gap`` (m), m/s."""
    lo, hi = 0.0, v0
    for _ in range(60):  # the equilibrium gap grows with the speed: bisect
        v = (lo + hi) / 2
        if (s0 + v * t) / math.sqrt(1.0 - (v / v0) ** 4) < gap:
            lo = v
        else:
            hi = v
    return lo


@dataclass(frozen=True)
class Rule:
    """One hand policy: ``kind`` ``idm`` or ``gap-speed`` and its parameters."""

    kind: str
    v_star: float = 30.0  #: idm: desired speed, m/s
    s0: float = 2.0  #: idm: jam gap, m; gap-speed: g0, m
    t_gap: float = 1.0  #: idm: time headway, s; gap-speed: tau, s
    cross: float | None = None  #: idm: the crossing rule's clearance, m (None: off)
    hold_gap: float | None = None  #: stand until the gap ahead is at least this, m
    linear: bool = False  #: gap-speed: the gap without the modulo
    gain: float = 1.0  #: gap-speed: 1/s

    @property
    def label(self) -> str:
        hold = "" if self.hold_gap is None else f"hold {self.hold_gap:g} m, then "
        if self.kind == "gap-speed":
            lin = ", linear" if self.linear else ""
            gain = "" if self.gain == 1.0 else f" x{self.gain:g}"
            cross = "" if self.cross is None else f" +cross {self.cross:g}"
            return f"{hold}gap-speed {self.s0:g} {self.t_gap:g}{gain}{lin}{cross}"
        keep = f" s0 {self.s0:g} T {self.t_gap:g}" if (self.s0, self.t_gap) != (2.0, 1.0) else ""
        cross = "" if self.cross is None else f" +cross {self.cross:g}"
        return f"{hold}idm {self.v_star:g}{keep}{cross}"

    def accel(self, obs: np.ndarray, loop: Loop) -> float:
        """The AV's acceleration after the hold."""
        n = obs.size // 2
        v, x = obs[:n] * loop.max_speed, obs[n:] * loop.length
        i = loop.av
        gap, j = leader_gap(x, i, loop.length)
        if self.kind == "gap-speed":
            if self.linear:
                gap = float(x[j] - x[i]) - CAR
            accel = gap_speed_accel(gap, float(v[i]), self.s0, self.t_gap, self.gain)
            if self.cross is None:
                return accel
            return min(accel, Rule("idm", cross=self.cross).accel(obs, loop))
        if self.cross is not None:
            gap_x, jx = crossing_gap(x, i, loop, self.cross)
            if gap_x < gap:
                gap, j = gap_x, jx
        idm = idm_accel(np.array(v[i]), np.array(gap), np.array(v[j]), v0=self.v_star,
                        T=self.t_gap, a=1.0, b=1.5, delta=4.0, s0=self.s0)  # fmt: skip
        return float(np.clip(idm, -3.0, 3.0))

    def policy(self, env: Any) -> Callable[[Any], Any]:
        """A fresh per-episode policy for ``env`` (it keeps whether it has set off; it reads
        the env's :class:`Loop` at its first step)."""
        held, loops = [self.hold_gap is not None], list[Loop]()

        def act(obs: Any) -> Any:
            if not loops:
                loops.append(loop_of(env))
            loop, o = loops[0], np.asarray(obs, dtype=float)
            if held[0] and self.hold_gap is not None:
                n = o.size // 2
                held[0] = leader_gap(o[n:] * loop.length, loop.av, loop.length)[0] < self.hold_gap
            return np.array([-3.0 if held[0] else self.accel(o, loop)])

        return act


def loop_of(env: Any) -> Loop:
    """The :class:`Loop` of a figure-eight ``AccelEnv``."""
    net, vk = env.k.network, env.k.vehicle
    starts = net.total_edgestarts_dict
    av = list(env.sorted_ids).index(vk.get_rl_ids()[0])
    return Loop(net.length(), (starts[":center_1"], starts[":center_0"]), net.max_speed(), av)


def rules(wide: bool) -> list[Rule]:
    """The rules ``hand_policies.py figureeight0`` scores (``wide``: more parameters)."""
    out = [Rule("idm", v_star=v) for v in ((6.0, 8.0, 10.0, 30.0) if wide else (8.0, 30.0))]
    out += [Rule("idm", v_star=v, cross=c) for v in (8.0, 30.0)
            for c in ((9.0, 12.0, 14.4, 17.0) if wide else (12.0, 14.4))]  # fmt: skip
    out.append(Rule("idm", s0=215.0, t_gap=0.0))
    out += [Rule("idm", cross=12.0, hold_gap=g) for g in (100.0, 200.0, 250.0, 300.0)]
    if wide:
        grid = [(g0, tau) for tau in (10.0, 12.5, 15.0, 17.5) for g0 in range(70, 135, 5)]
    else:
        grid = [(80, 15.0), (87, 15.0), (90, 15.0), (100, 15.0), (84, 16.0), (73, 17.5),
                (107, 12.5), (128, 10.0)]  # fmt: skip
    out += [Rule("gap-speed", s0=float(g0), t_gap=tau) for g0, tau in grid]
    out.append(Rule("gap-speed", s0=90.0, t_gap=15.0, cross=12.0))
    out.append(Rule("gap-speed", s0=90.0, t_gap=15.0, linear=True))
    return out


# ---------------------------------------------------------------- scoring and the ceiling
@dataclass(frozen=True)
class Episodes:
    """A rule's episodes, per seed: the mean speed over the whole episode (``flowrun
    benchmark``'s metric), over its second half and over its first 30 s (the evaluate-mode
    reward); collisions and teleports; and over the second halves the humans' mean gap and the
    column's longest span (the AV's front back to its leader's front: ``L`` minus the AV's gap
    minus a car); over whole episodes :func:`stream_switch_gap`."""

    label: str
    whole: list[float]
    second_half: list[float]
    first_30s: list[float]
    crashes: int
    human_gap: float
    span: float
    length: float  #: the loop, m
    switch: float  #: the shortest time between passages of the two streams at the junction, s


def run_rule(name: str, sets: list[str], rule: Rule | None, seeds: list[int], label: str,
             configs: Any) -> Episodes:  # fmt: skip
    """Each seed's evaluate-mode episode of the benchmark (``rule`` None: no AV action)."""
    from flowrun.envs.factory import make_env
    from flowrun.experiment.runner import Experiment
    from flowrun.loading.loader import load_config

    cfg = load_config(configs / f"{name}.yaml", [*sets, "env.evaluate=true"])
    env, whole, half, first, crashes = make_env(cfg), [], [], [], 0
    length = math.nan
    horizon, gaps, spans, switch = int(cfg.env.horizon), [], [], math.inf
    try:
        experiment = Experiment(env)
        for seed in seeds:
            act = rule.policy(env) if rule is not None else None
            seen: list[np.ndarray] = []

            def watch(obs: Any, act: Any = act, seen: list[np.ndarray] = seen) -> Any:
                seen.append(np.asarray(obs, dtype=float))
                return act(obs) if act is not None else None

            info = experiment.run(1, horizon, rl_actions=watch, seed=seed)
            r = np.asarray(info["per_step_returns"][0], dtype=float)
            m = experiment.metrics[0]  # flowrun benchmark's metric: the run's mean speed
            whole.append(float(m.mean_speed))
            half.append(float(m.last_half_mean_speed))
            first.append(float(r[:300].mean()))
            crashes += m.collisions + m.teleports
            g, s = _column(env, seen[horizon // 2 :], rule is not None)
            length = float(env.k.network.length())
            switch = min(switch, _switch(env, seen, float(cfg.sim.sim_step)))
            gaps.append(g)
            spans.append(s)
    finally:
        env.close()
    mean_gap = float(np.mean(gaps))
    return Episodes(label, whole, half, first, crashes, mean_gap, max(spans), length, switch)


def stream_switch_gap(
    xs: np.ndarray, points: tuple[float, float], length: float, dt: float
) -> float:
    """The shortest time (s) from a car passing one crossing link's conflict point to the next
    car passing the other's; ``xs``: positions ``x`` (m), one row per step ``dt`` s apart."""
    events: list[tuple[float, int]] = []
    for stream, point in enumerate(points):
        before, after = (point - xs[:-1]) % length, (point - xs[1:]) % length
        steps, _ = np.nonzero(after - before > length / 2)  # the distance to it wrapped: passed
        events += [((int(t) + 1) * dt, stream) for t in steps]
    events.sort()
    gaps = [b[0] - a[0] for a, b in pairwise(events) if a[1] != b[1]]
    return min(gaps) if gaps else math.inf


def _switch(env: Any, observed: list[np.ndarray], dt: float) -> float:
    length = float(env.k.network.length())
    starts = env.k.network.total_edgestarts_dict
    xs = np.array([obs[obs.size // 2 :] * length for obs in observed])
    points = (starts[":center_1"] + MID, starts[":center_0"] + MID)
    return stream_switch_gap(xs, points, length, dt)


def steady_layout_fits(headway: float, speed: float, length: float, switch: float) -> bool:
    """Whether the AV at 0 and 13 humans ``headway`` m apart behind it, all at ``speed``, pass
    the junction with cars of the two streams at least ``switch`` s apart. Positions modulo
    half the loop put both streams on one circle: neighbours on it that are not neighbours on
    the road reach the junction from the two links."""
    half = length / 2
    pos = np.array([(-k * headway) % length for k in range(14)])
    pos = pos[np.argsort(pos % half)]
    for a, b in zip(pos, np.roll(pos, -1), strict=True):
        apart = ((b % half) - (a % half)) % half
        if abs((b - a) % length - apart) > 1e-6 and apart < switch * speed:
            return False
    return True


def best_steady_layout(length: float, switch: float) -> tuple[float, float]:
    """The fastest layout of :func:`steady_layout_fits` with the humans at IDM's steady gap:
    (speed m/s, human headway m); the AV's own headway is what is left of the loop."""
    best = (0.0, 0.0)
    for headway in np.arange(7.5, length / 14, 0.01):
        speed = idm_equilibrium_speed(float(headway) - CAR)
        if speed > best[0] and steady_layout_fits(float(headway), speed, length, switch):
            best = (speed, float(headway))
    return best


def _column(env: Any, observed: list[np.ndarray], with_av: bool) -> tuple[float, float]:
    """Over ``observed``: the humans' mean gap to their leaders (m) and the column's longest
    span (m; nan without an AV)."""
    loop = loop_of(env) if with_av else None
    length = env.k.network.length()
    gaps, spans = [], []
    for obs in observed:
        n = obs.size // 2
        x = obs[n:] * length
        av = loop.av if loop is not None else -1
        gaps += [leader_gap(x, i, length)[0] for i in range(n) if i != av]
        if loop is not None:
            spans.append(length - leader_gap(x, av, length)[0] - CAR)
    return float(np.mean(gaps)), float(max(spans)) if spans else math.nan


def print_table(rows: list[Episodes], baseline: float, target: float) -> None:
    print("| policy | per seed | mean | vs baseline | target | 2nd half | first 30 s "
          "| human gap, 2nd half | longest column | stream switch | crashes |")  # fmt: skip
    print("|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        mean = float(np.mean(r.whole))
        print(f"| {r.label} | {', '.join(f'{v:.2f}' for v in r.whole)} | {mean:.3f} "
              f"| {(mean - baseline) / baseline * 100:+.1f} % | {'met' if mean >= target else '-'} "
              f"| {np.mean(r.second_half):.2f} | {np.mean(r.first_30s):.2f} "
              f"| {r.human_gap:.1f} m | {_metres(r.span)} | {r.switch:.1f} s "
              f"| {r.crashes} |")  # fmt: skip


def _metres(value: float) -> str:
    return "–" if math.isnan(value) else f"{value:.0f} m"


def print_ceiling(rows: list[Episodes], best: Episodes) -> None:
    """The column bound (13 human headways and a clearance ``c`` within half the loop), the
    fastest steady layout at the measured stream-switch gap, and the measurement."""
    length = best.length
    half = length / 2
    print(f"\nceiling: half the loop is {half:.1f} m; a column of the AV and 13 humans at one "
          "speed never meets its own tail at the junction if 13 (5 m + gap) + c <= that:")
    for c in (7.0, 14.4):
        gap = (half - c) / 13 - CAR
        print(f"  c = {c:g} m: human gap <= {gap:.2f} m, IDM's steady speed there "
              f"{idm_equilibrium_speed(gap):.2f} m/s")
    switch = min(r.switch for r in rows)
    print(f"the two streams passed the junction at least {switch:.1f} s apart (all rows); the "
          "fastest steady layout (13 humans at IDM's gap, the AV anywhere) whose streams pass")
    for gap_s in sorted({round(switch, 1), 1.0, 0.75}, reverse=True):
        speed, headway = best_steady_layout(length, gap_s)
        shape = "one column" if 13 * headway < half else "streams interleaved"
        print(f"  >= {gap_s:g} s apart: {speed:.2f} m/s, human headway {headway:.2f} m ({shape})")
    print(f"measured ({best.label}, second halves): human gap {best.human_gap:.2f} m (IDM's "
          f"steady speed {idm_equilibrium_speed(best.human_gap):.2f} m/s), mean speed "
          f"{np.mean(best.second_half):.2f} m/s, longest column {best.span:.1f} m "
          f"(half the loop minus {half - best.span:.1f} m)")  # fmt: skip


def main(seeds: list[int], wide: bool, configs: Any) -> None:
    """Score the all-human baseline and :func:`rules`, print the table and the ceiling."""
    from flowrun.experiment.benchmark import BENCHMARKS
    from flowrun.experiment.benchmark_results import TARGETS

    base = run_rule("figureeight0", list(BENCHMARKS["figureeight0"].baseline), None, seeds,
                    "all human (baseline)", configs)  # fmt: skip
    baseline = float(np.mean(base.whole))
    target = TARGETS["figureeight0"].threshold(baseline)
    assert target is not None
    rows = [base]
    for rule in rules(wide):
        rows.append(run_rule("figureeight0", [], rule, seeds, rule.label, configs))
        print(f"  {rule.label}: {np.mean(rows[-1].whole):.3f}", file=sys.stderr, flush=True)
    print(f"baseline {baseline:.3f}, target ({TARGETS['figureeight0'].text}) {target:.1f}\n")
    print_table(rows, baseline, target)
    best = max(rows[1:], key=lambda r: float(np.mean(r.whole)))
    print(f"\nbest hand policy: {best.label}, {np.mean(best.whole):.3f}")
    print_ceiling(rows, best)

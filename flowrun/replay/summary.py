"""Summary numbers of a logged run, and a side-by-side comparison of two runs."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from flowrun.recording import McapLog
from flowrun.recording.frames import StepStats
from flowrun.recording.repair import REPAIR_METADATA
from flowrun.recording.writer import ROSTER_METADATA
from flowrun.replay.analysis import SpeedSeries, speed_series


@dataclass(frozen=True)
class ReplaySummary:
    """What ``flowrun replay`` reports about one log.

    Speed definitions (match ``metrics.json`` of the run that wrote the log):
    ``mean_speed`` is the mean over logged steps of the per-step mean speed of the selected
    vehicles; ``min_speed``/``max_speed`` are the min/max over all vehicles and steps;
    ``speed_std`` is the mean over logged steps of the (population) standard deviation of
    speed across vehicles.

    Attributes:
        name: run label (config name, seed, file name).
        config_name: ``config_name`` metadata ("" if absent).
        seed: ``seed`` metadata ("" if absent).
        versions: the ``*_version`` metadata entries.
        first_time: first logged simulation time, s.
        last_time: last logged simulation time, s.
        duration_s: simulated time covered by the logged steps (one step interval per logged
            step; printed as "time covered", not a "duration", which is the clock at the last
            step in metrics.json), s.
        logged_steps: number of logged steps read.
        sim_steps: simulation steps spanned (last - first + 1).
        vehicles_by_type: distinct vehicle ids seen, per type.
        rl_vehicles: distinct RL-driven vehicle ids seen.
        mean_speed, min_speed, max_speed, speed_std: m/s, see above.
        collisions: collisions over the logged steps.
        teleports: teleports over the logged steps.
        episode_return: sum of the finite rewards, per RL step (``None`` when none is finite).
        salvaged: whether the log was damaged and read up to the damage.
        recovered_bytes: bytes of the file that were usable.
        departed: vehicles that entered the network over the logged steps (inflows).
        arrived: vehicles that left the network over the logged steps.
        lane_changes: lane changes over the logged steps (shown when there were any).
        outflow: ``arrived`` per hour of ``duration_s``, veh/h (``nan`` for an empty log).
        open_network: whether cars may enter and leave (not a ring): shows the three above.
        damage: what the log lost, one line (``""`` when intact; see
            :meth:`flowrun.recording.damage.DamageReport.short`).
    """

    name: str
    config_name: str
    seed: str
    versions: dict[str, str]
    first_time: float
    last_time: float
    duration_s: float
    logged_steps: int
    sim_steps: int
    vehicles_by_type: dict[str, int]
    rl_vehicles: int
    mean_speed: float
    min_speed: float
    max_speed: float
    speed_std: float
    collisions: int
    teleports: int
    episode_return: float | None
    salvaged: bool
    recovered_bytes: int
    departed: int = 0
    arrived: int = 0
    outflow: float = math.nan
    open_network: bool = False
    damage: str = ""
    lane_changes: int = 0


def _positive_int(text: str | None) -> int:
    """A metadata count (``sims_per_step``, ``record_every``); 1 when absent or unreadable."""
    try:
        return max(int(text or 1), 1)
    except ValueError:
        return 1


def run_label(log: McapLog) -> str:
    """A short name for a log: ``<config> (seed N) - <file>``."""
    meta = log.metadata
    name = meta.get("config_name", "")
    seed = meta.get("seed", "")
    parts = [p for p in (name, f"seed {seed}" if seed else "") if p]
    head = f"{parts[0]} ({parts[1]})" if len(parts) == 2 else "".join(parts)
    return f"{head} - {log.path.name}" if head else log.path.name


def _nanmean(a: np.ndarray) -> float:
    finite = a[np.isfinite(a)]
    return float(finite.mean()) if finite.size else math.nan


def summarize(
    log: McapLog,
    *,
    start_s: float | None = None,
    end_s: float | None = None,
    vehicles: Iterable[str] | None = None,
    series: SpeedSeries | None = None,
) -> ReplaySummary:
    """Summarise a log (optionally a time window / some vehicles).

    Speeds come from the ``/flowrun/vehicles`` frames; collisions, teleports and rewards from
    ``/flowrun/stats``. The return divides the summed per-step reward by the metadata
    ``sims_per_step`` (each RL step's reward is logged on each of its simulation steps) and
    multiplies by ``record_every`` (exact only when nothing was thinned out).

    Args:
        log: an opened log.
        start_s: first simulation time to include, s.
        end_s: last simulation time to include, s.
        vehicles: restrict the speed numbers to these ids.
        series: a precomputed :func:`speed_series` of the same selection (saves a pass).
    """
    stats = list(log.stats(start_s, end_s))
    fixed_roster = log.all_metadata.get(ROSTER_METADATA, {}).get("rosters") == "1"
    if series is None and vehicles is None and stats and fixed_roster:
        # The stats topic already holds every step's speed aggregates over all vehicles:
        # no need to decode the (large) vehicle frames beyond the first one.
        series = series_from_stats(log, stats, start_s, end_s)
    s = series or speed_series(log, start_s=start_s, end_s=end_s, vehicles=vehicles)
    meta = log.metadata
    n = s.times.size
    first, last, duration = _time_span(s.times)
    has_speed = s.count > 0
    departed = sum(st.departed for st in stats)
    arrived = sum(st.arrived for st in stats)
    return ReplaySummary(
        name=run_label(log),
        config_name=meta.get("config_name", ""),
        seed=meta.get("seed", ""),
        versions={k: v for k, v in meta.items() if k.endswith("_version")},
        first_time=first,
        last_time=last,
        duration_s=duration,
        logged_steps=n,
        sim_steps=int(s.steps[-1] - s.steps[0] + 1) if n else 0,
        vehicles_by_type=dict(sorted(Counter(s.vehicle_types.values()).items())),
        rl_vehicles=len(s.rl_ids),
        mean_speed=_nanmean(s.mean),
        min_speed=float(np.nanmin(s.min[has_speed])) if has_speed.any() else math.nan,
        max_speed=float(np.nanmax(s.max[has_speed])) if has_speed.any() else math.nan,
        speed_std=_nanmean(s.std),
        collisions=sum(st.collisions for st in stats),
        teleports=sum(st.teleports for st in stats),
        episode_return=_episode_return(stats, meta),
        salvaged=log.salvaged,
        recovered_bytes=log.recovered_bytes,
        departed=departed,
        arrived=arrived,
        outflow=arrived * 3600.0 / duration if duration > 0 else math.nan,
        open_network=meta.get("network_closed") == "false" or departed + arrived > 0,
        damage=_damage(log),
        lane_changes=sum(st.lane_changes for st in stats),
    )


def _time_span(times: np.ndarray) -> tuple[float, float, float]:
    """First and last logged time and the time the logged steps cover (one step interval,
    the median, per logged step), s; ``nan``, ``nan``, 0 without steps."""
    n = times.size
    if not n:
        return math.nan, math.nan, 0.0
    first, last = float(times[0]), float(times[-1])
    interval = float(np.median(np.diff(times))) if n > 1 else 0.0
    return first, last, last - first + interval


def _episode_return(stats: list[StepStats], meta: dict[str, str]) -> float | None:
    """The summed finite rewards times ``record_every`` over ``sims_per_step`` (each RL
    step's reward is logged on each of its simulation steps); ``None`` without one."""
    rewards = [st.reward for st in stats if math.isfinite(st.reward)]
    if not rewards:
        return None
    sims_per_step = _positive_int(meta.get("sims_per_step"))
    record_every = _positive_int(meta.get("record_every"))
    return float(sum(rewards)) * record_every / sims_per_step


def _damage(log: McapLog) -> str:
    """What the log lost, or what the log it was repaired from lost."""
    if log.damage:
        return log.damage.short()
    repaired = log.all_metadata.get(REPAIR_METADATA)
    if repaired and repaired.get("lost"):
        return (
            f"none here; repaired from {repaired.get('source', '?')}, which lost: "
            + repaired["lost"]
        )
    return ""


def _num(x: float | None, unit: str = "", digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x:.{digits}f}{unit}"


def summary_rows(s: ReplaySummary) -> dict[str, str]:
    """The summary as ordered ``label -> formatted value`` rows (what the CLI prints)."""
    rows = {
        "run": s.name,
        "config": s.config_name or "-",
        "seed": s.seed or "-",
    }
    for key, value in s.versions.items():
        rows[key.removesuffix("_version") + " version"] = value
    rows.update(
        {
            "time covered": _num(s.duration_s, " s", 1),
            "time range": f"{_num(s.first_time, '', 1)} - {_num(s.last_time, ' s', 1)}",
            "logged steps": str(s.logged_steps),
            "simulation steps": str(s.sim_steps),
            "vehicles": ", ".join(f"{t}: {c}" for t, c in s.vehicles_by_type.items()) or "-",
            "RL vehicles": str(s.rl_vehicles),
            "mean speed": _num(s.mean_speed, " m/s"),
            "min speed": _num(s.min_speed, " m/s"),
            "max speed": _num(s.max_speed, " m/s"),
            "speed std across vehicles": _num(s.speed_std, " m/s"),
            "collisions": str(s.collisions),
            "teleports": str(s.teleports),
            "return": _num(s.episode_return, "", 3),
        }
    )
    if s.open_network:
        rows["vehicles entered"] = str(s.departed)
        rows["vehicles left"] = str(s.arrived)
        rows["outflow over the log"] = _num(s.outflow, " veh/h", 0)
    if s.lane_changes:
        rows["lane changes"] = str(s.lane_changes)
    if s.salvaged:
        rows["salvaged"] = f"yes ({s.recovered_bytes} bytes recovered)"
    if s.damage:
        rows["damage"] = s.damage
    return rows


_NUMERIC = {
    "mean speed": "mean_speed",
    "min speed": "min_speed",
    "max speed": "max_speed",
    "speed std across vehicles": "speed_std",
    "time covered": "duration_s",
    "collisions": "collisions",
    "teleports": "teleports",
    "return": "episode_return",
    "vehicles entered": "departed",
    "vehicles left": "arrived",
    "outflow over the log": "outflow",
    "lane changes": "lane_changes",
}


def compare(
    a: McapLog | ReplaySummary, b: McapLog | ReplaySummary, **select: object
) -> dict[str, tuple[str, str, str]]:
    """Two runs side by side: ``label -> (value A, value B, B - A)``.

    Args:
        a: first log (or its summary).
        b: second log (or its summary).
        **select: ``start_s``/``end_s``/``vehicles`` passed to :func:`summarize` for logs.
    """
    sa = a if isinstance(a, ReplaySummary) else summarize(a, **select)  # type: ignore[arg-type]
    sb = b if isinstance(b, ReplaySummary) else summarize(b, **select)  # type: ignore[arg-type]
    ra, rb = summary_rows(sa), summary_rows(sb)
    table: dict[str, tuple[str, str, str]] = {}
    for label in list(ra) + [k for k in rb if k not in ra]:
        delta = ""
        attr = _NUMERIC.get(label)
        if attr is not None:
            va, vb = getattr(sa, attr), getattr(sb, attr)
            if va is not None and vb is not None and math.isfinite(va) and math.isfinite(vb):
                delta = f"{vb - va:+.3f}"
        table[label] = (ra.get(label, "-"), rb.get(label, "-"), delta)
    return table


def series_from_stats(
    log: McapLog, stats: list[StepStats], start_s: float | None, end_s: float | None
) -> SpeedSeries:
    """All-vehicle :class:`SpeedSeries` from ``/flowrun/stats`` and the first frame's roster."""
    types: dict[str, str] = {}
    rl_ids: set[str] = set()
    for msg in log.vehicle_messages(start_s, end_s):
        for vid, vtype, rl in zip(msg.ids, msg.types, msg.is_rl, strict=True):
            types[vid] = vtype
            if rl:
                rl_ids.add(vid)
        break
    table = np.array(
        [(st.mean_speed, st.min_speed, st.max_speed, st.speed_std) for st in stats],
        dtype=np.float64,
    ).reshape(-1, 4)
    return SpeedSeries(
        times=np.array([st.time for st in stats], dtype=np.float64),
        steps=np.array([st.step for st in stats], dtype=np.int64),
        mean=table[:, 0],
        min=table[:, 1],
        max=table[:, 2],
        std=table[:, 3],
        count=np.array([st.num_vehicles for st in stats], dtype=np.int64),
        vehicle_types=types,
        rl_ids=frozenset(rl_ids),
    )

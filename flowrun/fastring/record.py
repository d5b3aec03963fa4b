"""MCAP logs of numpy-ring episodes, in the layout the SUMO backend writes.

One episode of one ring (warm-up included, every simulation step) goes to
``/flowrun/vehicles`` and ``/flowrun/stats`` through :class:`~flowrun.recording.McapRecorder`,
with the metadata ``flowrun replay`` reads (versions, seed, config, the ring's edge starts).
Edges and lane positions follow from the ring position; ``x``/``y`` lie on the circle through
the lane's centre (SUMO's lane polyline differs by a few centimetres).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.fastring.batch import RingState
from flowrun.fastring.plan import ring_plan
from flowrun.fastring.vec_env import RingEpisodes
from flowrun.recording.frames import StepStats, VehicleFrame
from flowrun.recording.writer import McapRecorder
from flowrun.rundir.folders import log_metadata
from flowrun.types import BoolArray

#: SUMO's default lane width, m: lane centres lie half of it outside the ring's radius
LANE_WIDTH = 3.2

# observation -> action (RL cars' accelerations)
Policy = Callable[[np.ndarray], np.ndarray]


Sink = Callable[[VehicleFrame, StepStats], object]


class _FrameWriter:
    """Turns ring 0's state after each simulation step into a frame and its stats."""

    def __init__(self, episodes: RingEpisodes, sink: Sink) -> None:
        plan = episodes.plan
        self.episodes = episodes
        self.sink = sink
        self.dt = plan.dt
        self.ids = [f"{g.name}_{i}" for g in plan.groups for i in range(g.stop - g.start)]
        self.types = [g.name for g in plan.groups for _ in range(g.stop - g.start)]
        self.is_rl = np.zeros(plan.num_cars, dtype=bool)
        self.is_rl[plan.rl_rows] = True
        self.edges = [e.id for e in plan.network.spec.edges]
        self.step = 0
        self.prev: np.ndarray | None = None
        self.reward = math.nan

    def __call__(self, state: RingState, crashed: BoolArray) -> None:
        length = float(state.length[0])
        edge_len = length / len(self.edges)
        speed = state.speed[:, 0].copy()
        position = np.mod(state.u[:, 0], length)
        idx = np.minimum((position // edge_len).astype(np.int64), len(self.edges) - 1)
        angle = -math.pi / 2 + 2 * math.pi * position / length
        radius = length / (2 * math.pi) + LANE_WIDTH / 2
        accel = self.episodes.rings.physics.last_accel
        cmd = np.full(speed.size, np.nan) if accel is None else accel[:, 0].copy()
        prev = speed if self.prev is None else self.prev
        leader = state.leader[:, 0]
        frame = VehicleFrame(
            step=self.step, time=(self.step + 2) * self.dt, ids=self.ids, types=self.types,
            edges=[self.edges[i] for i in idx.tolist()], lanes=np.zeros(speed.size, np.int64),
            lane_pos=position - idx * edge_len, position=position, odometer=state.odo[:, 0].copy(),
            x=radius * np.cos(angle), y=radius * np.sin(angle), speed=speed, accel_cmd=cmd,
            accel_real=(speed - prev) / self.dt, headway=state.headway[:, 0].copy(),
            leader=[self.ids[j] for j in leader.tolist()], is_rl=self.is_rl,
        )  # fmt: skip
        mean = float(speed.sum()) / speed.size
        stats = StepStats(
            step=self.step, time=frame.time, num_vehicles=speed.size, mean_speed=mean,
            min_speed=float(speed.min()), max_speed=float(speed.max()),
            speed_std=math.sqrt(float(((speed - mean) ** 2).sum()) / speed.size),
            reward=self.reward, collisions=int(crashed[0]), teleports=0,
        )  # fmt: skip
        self.sink(frame, stats)
        self.prev = speed
        self.step += 1


def record_episode(
    cfg: ExperimentConfig,
    path: Path,
    seed: int,
    policy: Policy | None = None,
    record_every: int = 1,
) -> float:
    """Run one numpy-ring episode of ``cfg`` (warm-up included) and log it to ``path``.

    Args:
        cfg: the experiment (run on the numpy backend whatever its ``sim.backend``).
        path: the MCAP file to write.
        seed: the episode's reset seed (as ``env.reset(seed=seed)`` on SUMO).
        policy: observation -> the RL cars' accelerations; ``None`` commands nothing (SUMO's
            IDM drives the RL cars and the reward is 0, as Flow's env without an action).
        record_every: keep every this many simulation steps.

    Returns:
        the episode's return.

    Raises:
        ConfigError: the numpy backend cannot run ``cfg``.
    """
    plan = ring_plan(replace(cfg, sim=replace(cfg.sim, backend="numpy")))
    episodes = RingEpisodes(plan, 1)
    rings = episodes.rings
    pending: list[tuple[VehicleFrame, StepStats]] = []
    writer = _FrameWriter(episodes, lambda f, s: pending.append((f, s)))
    rings.physics.keep_accel = True
    rings.observer = writer  # the start and the warm-up, while the reset draws the ring
    obs = episodes.reset_all([seed])
    rings.observer = None
    length = float(rings.lengths[0])
    meta = {
        **log_metadata(cfg, seed, 0, record_every),
        **network_metadata(length, writer.edges),
        "backend": "numpy",
    }
    attachments = {"config.yaml": dump_config(cfg).encode()}
    with McapRecorder(
        path, metadata=meta, attachments=attachments, record_every=record_every
    ) as recorder:
        for frame, stats in pending:
            recorder.write(frame, stats)
        writer.sink = recorder.write
        return _drive(episodes, plan.horizon, obs, policy, writer)


def _drive(
    episodes: RingEpisodes,
    horizon: int,
    obs: np.ndarray,
    policy: Policy | None,
    writer: _FrameWriter,
) -> float:
    """Step the one ring up to ``horizon`` env steps or a collision, each step logged by
    ``writer``; the episode's return."""
    rings, task = episodes.rings, episodes.task
    total = 0.0
    for _ in range(horizon):
        if policy is None:
            crashed = rings.step(None)
            reward = 0.0
        else:
            applied = task.clip(np.asarray(policy(obs[0]), dtype=np.float64).reshape(1, -1))
            crashed = rings.step(applied)
            reward = float(task.rewards(rings, applied, crashed)[0])
            obs = task.observe(rings)
        total += reward
        writer.reward = reward
        assert rings.state is not None
        writer(rings.state, crashed)
        if crashed[0]:
            break
    return total


def network_metadata(length: float, edges: list[str]) -> dict[str, str]:
    """``main_route``, ``edge_starts``, ``network_closed`` and ``network_length`` of a ring
    (the keys of :func:`flowrun.envs.frames.network_metadata`)."""
    starts = {e: i * length / len(edges) for i, e in enumerate(edges)}
    return {
        "main_route": json.dumps(edges),
        "edge_starts": json.dumps(starts),
        "network_closed": "true",
        "network_length": repr(float(length)),
    }

"""``FastRings``: B rings with their episodes — seeded resets, warm-up, steps.

The episode bookkeeping of the SUMO env (:class:`flowrun.envs.base.Env`) for many rings:
a reset draws the ring and placement from the ring's own generator, then runs
``warmup_steps`` steps without RL action (stopping early on a collision, as the SUMO env
does); a step applies the RL cars' accelerations and reports collisions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from flowrun.fastring.batch import (
    NoiseStreams,
    RingPhysics,
    RingState,
    draw_episode,
    fresh_state,
    new_generator,
)
from flowrun.fastring.plan import RingPlan
from flowrun.networks.base import Network
from flowrun.types import BoolArray, FloatArray, IntArray


class FastRings:
    """``num_rings`` rings of one :class:`RingPlan`.

    Args:
        plan: the config's facts (:func:`~flowrun.fastring.plan.ring_plan`).
        num_rings: rings stepped together.

    Attributes:
        state: the rings' moving state.
        episode_steps: env steps of each ring's episode so far.
        collisions: collisions each ring had in its episode (warm-up included).
    """

    def __init__(self, plan: RingPlan, num_rings: int) -> None:
        self.plan = plan
        self.num_rings = num_rings
        self.physics = RingPhysics(plan)
        self.noise = NoiseStreams(plan.num_noisy, num_rings)
        self.rngs: list[np.random.Generator | None] = [None] * num_rings
        self._networks: dict[float, Network] = {}
        self.state: RingState | None = None
        self.episode_steps = np.zeros(num_rings, dtype=np.int64)
        self.collisions = np.zeros(num_rings, dtype=np.int64)
        #: called with the state and the rings that collided after every simulation step
        #: (warm-up included) and at the start of an episode (a log's frames)
        self.observer: Callable[[RingState, BoolArray], None] | None = None

    def reset(
        self,
        cols: Sequence[int] | IntArray,
        seeds: Sequence[int | None],
        lengths: Sequence[float | None] | None = None,
    ) -> None:
        """Start new episodes on the rings ``cols`` (``seeds[i]`` reseeds ring ``cols[i]``;
        ``None`` continues its generator, or seeds it with ``sim.seed`` the first time).
        ``lengths[i]`` (m) sets ring ``cols[i]``'s length as the SUMO env's
        ``reset(options={"ring_length": L})`` does (``None``: the drawn length)."""
        cols = np.asarray(cols, dtype=np.int64)
        chosen = [None] * cols.size if lengths is None else list(lengths)
        episodes = []
        for col, seed, length in zip(cols.tolist(), seeds, chosen, strict=True):
            if seed is None and self.rngs[col] is None:
                seed = int(self.plan.cfg.sim.seed or 0)
            if seed is not None:
                self.rngs[col] = new_generator(int(seed))
            rng = self.rngs[col]
            assert rng is not None
            episode = draw_episode(
                self.plan, rng, self._networks, None if length is None else float(length)
            )
            self.noise.restart(col, episode.noise_seed)
            episodes.append(episode)
        part = fresh_state(self.plan, episodes)
        if self.observer is not None:
            self.physics.last_accel = None
            self.observer(part, np.zeros(cols.size, dtype=bool))
        self.collisions[cols] = 0
        self.episode_steps[cols] = 0
        part = self._warm_up(cols, part)
        if self.state is None:
            if cols.size != self.num_rings or not np.array_equal(cols, np.arange(cols.size)):
                raise ValueError("the first reset must start every ring, in order")
            self.state = part
        else:
            self.state.put(cols, part)

    def _warm_up(self, cols: IntArray, part: RingState) -> RingState:
        """Run the warm-up of the rings ``cols``; a ring that collides stops warming up."""
        active = np.arange(cols.size)
        for _ in range(self.plan.warmup):
            sub = part if active.size == cols.size else part.take(active)
            crashed = self.physics.step(sub, self.noise.draw(cols[active]), None)
            if self.observer is not None:
                self.observer(sub, crashed)
            if active.size != cols.size:
                part.put(active, sub)
            if crashed.any():
                self.collisions[cols[active[crashed]]] += 1
                active = active[~crashed]
                if active.size == 0:
                    break
        return part

    def step(self, rl_accel: FloatArray | None) -> BoolArray:
        """One env step of every ring: the RL cars' accelerations ``(num_rl, B)`` (``None``:
        SUMO drives them). Returns which rings collided."""
        assert self.state is not None, "reset() every ring first"
        crashed = self.physics.step(self.state, self.noise.draw(), rl_accel)
        if self.observer is not None:
            self.observer(self.state, crashed)
        self.episode_steps += 1
        self.collisions += crashed
        return crashed

    @property
    def lengths(self) -> FloatArray:
        """Ring lengths of the current episodes, m."""
        assert self.state is not None
        return self.state.length

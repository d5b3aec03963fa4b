"""What an env hands out besides observations: its step records (with frames) for
``Experiment`` to log, and a top-down picture of the traffic (``render``).

:class:`EnvOutput` is a part of :class:`flowrun.envs.base.Env`, which sets the attributes it
declares.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.config.params import SumoParams

if TYPE_CHECKING:  # the kernel, frames and painter are imported where an env starts
    from flowrun.envs.frames import StepRecord
    from flowrun.envs.render import EnvPainter
    from flowrun.kernel import Kernel
    from flowrun.kernel.geometry import RingPlacement

#: luminance weights of R, G, B (ITU-R BT.601): the grey of Flow's gray/dgray render modes
GREY = np.array([0.299, 0.587, 0.114])


class EnvOutput:
    """Step records and pictures of an env (a base of :class:`~flowrun.envs.base.Env`)."""

    k: Kernel
    sim_params: SumoParams
    render_mode: str | None
    record_frames: bool
    collect_stats: bool
    records: list[StepRecord]
    _needs_reset: bool
    _painter: EnvPainter | None
    _placement: RingPlacement | None

    def take_records(self) -> list[StepRecord]:
        """Hand over the queued step records (frames completed) and start a new queue."""
        from flowrun.envs.frames import complete_frames

        records, self.records = self.records, []
        if self._placement is not None:
            complete_frames(records, self._placement, self.k.vehicle.dt)
        return records

    def _emit_frame(self) -> None:
        """Queue this simulation step's record (and frame); ``step`` fills in the reward."""
        if self.record_frames or self.collect_stats:
            from flowrun.envs.frames import step_record

            step = self.k.simulation.step_count
            deferred = self._placement is not None
            self.records.append(step_record(self.k, step, self.record_frames, deferred))

    def render(self) -> Any:
        """A top-down RGB picture of the traffic on its road (``render_mode="rgb_array"``:
        lane shapes of the network, cars coloured by speed on a scale that grows with the
        fastest car of the episode, AVs outlined, signal states), else ``None``."""
        if self.render_mode != "rgb_array" or (self._needs_reset and not self.k.started):
            return None
        if self._painter is None:
            from flowrun.envs.render import EnvPainter

            self._painter = EnvPainter()
        frame = self._painter(self.k)
        if self.sim_params.render in ("gray", "dgray"):  # Flow's grey modes: luminance
            frame = np.repeat((frame @ GREY).astype(np.uint8)[..., None], 3, axis=2)
        return frame

"""Instructions per simulation step on the Sugiyama ring, counted by valgrind (load-proof).

Wall-clock timings on a shared 2-core machine move by ±30%; instruction counts do not. This
script runs one mode for N steps; ``bench/step_instructions.sh`` runs it under callgrind for two
values of N and prints the difference per step, so start-up costs cancel out.

Modes:
    raw  SUMO's own IDM drives (cars get many-lap routes first); only ``simulationStep``.
    exp  ``Experiment.run`` of ``configs/sugiyama.yaml`` (what ``flowrun baseline --no-record``
         runs per step: flowrun IDM, commands, per-step statistics).
    rec  ``exp`` plus an MCAP recorder (what ``flowrun baseline`` runs per step).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from flowrun.config.loader import load_config
from flowrun.envs.factory import make_env
from flowrun.experiment.runner import Experiment
from flowrun.recording.writer import McapRecorder

SUGIYAMA = Path(__file__).resolve().parent.parent / "configs" / "sugiyama.yaml"
SUMO_IDM = (
    "vehicles[0].acceleration_controller={type: SimCarFollowingController}",
    "vehicles[0].car_following.car_follow_model=IDM",
)


def main() -> None:
    mode, steps = sys.argv[1], int(sys.argv[2])
    if mode == "raw":
        env = make_env(load_config(SUGIYAMA, SUMO_IDM))
        env.reset(seed=0)
        assert env.k.process is not None
        api = env.k.process.api
        edges = [e.id for e in env.k.network.spec.edges]
        for vid in env.k.vehicle.get_ids():
            i = edges.index(api.vehicle.getRoadID(vid))
            api.vehicle.setRoute(vid, (edges[i:] + edges[:i]) * 200)
        for _ in range(steps):
            api.simulationStep()
        assert api.vehicle.getIDCount() == 22
    else:
        env = make_env(load_config(SUGIYAMA, [f"env.horizon={steps}"]))
        with tempfile.TemporaryDirectory() as tmp:

            def sink(run: int) -> McapRecorder:
                return McapRecorder(Path(tmp) / f"run_{run}.mcap", metadata={}, attachments={})

            Experiment(env, sink_factory=sink if mode == "rec" else None).run(1, steps)
    env.close()


if __name__ == "__main__":
    main()

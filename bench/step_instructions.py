"""Instructions per simulation step on the Sugiyama ring, counted by valgrind (load-proof).

Wall-clock timings on a shared 2-core machine move by ±30%; instruction counts do not. This
script runs one mode for N steps; ``bench/step_instructions.sh`` runs it under callgrind for two
values of N and prints the difference per step, so start-up costs cancel out.

Modes:
    raw  SUMO's own IDM drives (cars get many-lap routes first); only ``simulationStep``.
    exp  ``Experiment.run`` of ``configs/sugiyama.yaml`` (what ``flowrun baseline --no-record``
         runs per step: flowrun IDM, commands, per-step statistics).
    rec  ``exp`` plus an MCAP recorder (what ``flowrun baseline`` runs per step).
    merge  ``Experiment.run`` of ``configs/merge.yaml`` (Flow's merge0, an open network; one
         "step" here is one env step of two simulation steps).
    merge_raw  the merge's floor, as ``bench/open_networks.py``'s (a): flowrun builds the files
         and inserts the placed cars, then only ``simulationStep`` (two per "step") runs, and
         each entering car gets its type's speed and lane-change modes.
    eight, eight_raw  Flow's figureeight0 benchmark (``bench/env_vs_sumo.py``): the env with
         seeded random actions (drawn before the steps, as many at every run), and SUMO
         alone replaying every command the env sent (run ``bench/step_instructions.py
         eight_record STEPS`` first, as ``step_instructions.sh`` does).
    eight_ars  one of figureeight0's ARS candidates as a ``flowrun train`` worker plays it
         (``LeanAsyncEval``: the env, the policy's action, the observation statistics), one
         episode of STEPS steps, its weights the recipe's first update's first candidate.
    grid, grid_raw  Flow's grid0 benchmark (3x3 lights, 300 veh/h per entering edge):
         ``TrafficLightGridBenchmarkEnv`` with seeded random switch actions, and SUMO alone
         replaying the env's signal states and car modes (``bench/grid_steps.py``; run
         ``bench/grid_steps.py record grid0 STEPS`` first, as ``step_instructions.sh`` does).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from flowrun.envs.factory import make_env
from flowrun.experiment.runner import Experiment
from flowrun.loading.loader import load_config
from flowrun.recording.writer import McapRecorder

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ring import Ring, config, time_floor  # bench/ring.py, beside this file

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
#: the figure eight's random actions drawn in every run of ``eight`` (at least its steps)
EIGHT_ACTIONS = 2500


def figure_eight(mode: str, steps: int) -> None:
    """figureeight0's env step (``eight``), SUMO alone replaying the env's commands
    (``eight_raw``), or the recording of those commands (``eight_record``)."""
    import pickle

    import env_vs_sumo  # bench/ is this script's folder

    log_file = Path(tempfile.gettempdir()) / "flowrun-bench-figureeight0-commands.pickle"
    if mode == "eight_record":
        log, _ = env_vs_sumo.record("figureeight0", steps)
        log_file.write_bytes(pickle.dumps(log))
        return
    env = env_vs_sumo.make("figureeight0", steps)
    if mode == "eight_raw":
        assert env.k.process is not None
        env_vs_sumo.replay(env.k.process.api, pickle.loads(log_file.read_bytes())[:steps])
    else:
        # the actions of EIGHT_ACTIONS steps drawn up front, whatever ``steps`` is: their
        # draws (about 110,000 instructions each) cancel out of the per-step difference, as
        # env_vs_sumo.py's timing leaves them out; the first ``steps`` are the recorded ones
        for action in env_vs_sumo.actions(env, max(steps, EIGHT_ACTIONS))[:steps]:
            env.step(action)
    env.close()


def ars_worker(steps: int) -> None:
    """One ARS candidate of figureeight0 played by a worker, an episode of ``steps`` steps."""
    import torch
    from sb3_contrib import ARS

    from flowrun.training.ars import WorkerEnv
    from flowrun.training.numpy_predict import _Candidates
    from flowrun.training.vecenv import EnvFactory

    cfg = load_config(CONFIGS / "benchmarks" / "figureeight0.yaml", [f"env.horizon={steps}"])
    env = make_env(cfg)
    model = ARS("LinearPolicy", env, policy_kwargs={"with_bias": True}, seed=0, device="cpu")
    env.close()
    worker = _Candidates(WorkerEnv(EnvFactory(cfg), 0, True), model.policy, 1)
    theta = model.policy.parameters_to_vector()
    noise = np.random.default_rng(0).standard_normal(theta.size)
    worker.play(torch.as_tensor(theta + 0.02 * noise, dtype=torch.float32))
    worker.env.close()


def main() -> None:
    mode, steps = sys.argv[1], int(sys.argv[2])
    scale = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    ring = Ring("", scale, steps, 0)  # scale 100: 2,200 cars on 23 km, as bench/ring.py
    if mode == "raw":
        time_floor(ring)  # SUMO's own IDM, many-lap routes, simulationStep only
        return
    if mode == "merge_raw":
        merge = load_config(CONFIGS / "merge.yaml", [f"env.horizon={steps}"])
        env = make_env(merge)
        env.reset(seed=0)
        assert env.k.process is not None
        api = env.k.process.api
        modes = {c.name: (c.speed_mode, c.lane_change_mode) for c in env.k.vehicle.table.classes}
        for _ in range(steps * merge.env.sims_per_step):
            api.simulationStep()
            for vid in api.simulation.getDepartedIDList():
                speed_mode, lane_change_mode = modes.get(api.vehicle.getTypeID(vid), (31, 1621))
                api.vehicle.setSpeedMode(vid, speed_mode)
                api.vehicle.setLaneChangeMode(vid, lane_change_mode)
        env.close()
        return
    if mode == "eight_ars":
        ars_worker(steps)
        return
    if mode.startswith("eight"):
        figure_eight(mode, steps)
        return
    if mode in ("grid", "grid_raw"):
        from grid_steps import run_grid  # bench/ is this script's folder

        run_grid("raw" if mode == "grid_raw" else "env", "grid0", steps)
        return
    if mode == "merge":
        merge = load_config(CONFIGS / "merge.yaml", [f"env.horizon={steps}"])
        env = make_env(merge)
        Experiment(env).run(1, steps, seed=0)
        env.close()
        return
    env = make_env(config("sugiyama", ring, f"env.horizon={steps}"))
    with tempfile.TemporaryDirectory() as tmp:

        def sink(run: int) -> McapRecorder:
            return McapRecorder(Path(tmp) / f"run_{run}.mcap", metadata={}, attachments={})

        Experiment(env, sink_factory=sink if mode == "rec" else None).run(1, steps)
    env.close()


if __name__ == "__main__":
    main()

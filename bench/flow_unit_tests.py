"""Flow's own unit tests (``tests/fast_tests``) run against flowrun, their imports changed only.

    .venv/bin/python bench/flow_unit_tests.py --flow FLOW_CHECKOUT
    .venv/bin/python bench/flow_unit_tests.py --flow FLOW_GIT_DIR --commit a511c41 \\
        [--only test_vehicles] [--keep DIR]

``--flow`` is a Flow work tree or a (bare) git repository of Flow with ``--commit``; nothing of
Flow's is kept in this repository. The script lays out a temporary folder as a Flow checkout
with ``flow`` replaced by flowrun: Flow's ``tests/`` (the fast tests, ``setup_scripts.py``, the
test data), ``examples/exp_configs/non_rl/`` and ``templates/`` beside a copy of this tree's
``flowrun`` package, so ``flowrun.config.PROJECT_PATH`` is that folder, as
``flow.config.PROJECT_PATH`` is Flow's checkout (tests read ``PROJECT_PATH/tests/data/euclid.osm``
and the I-210 templates). In the Python files of ``tests/`` and ``examples/`` it rewrites
imports only: ``flow.`` → ``flowrun.`` (also in ``__import__("flow....")``), ``gym.spaces`` →
``gymnasium.spaces``. Each test file then runs in its own process (``unittest``, a timeout per
file); a file that fails to import counts as all of its tests failing (its ``def test_``
counted in the source). Run it under ``nice``: the children inherit it.

The table gives per file the tests, passed, failed or errored, and how many of the failures are
known (a deliberate difference or out of scope, listed in ``KNOWN`` with the reason); every
other failure is printed with its error's last line.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time
import traceback
import unittest
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: what is taken from Flow: paths inside its tree (the example configs: a test imports one)
FLOW_PATHS = ["tests", "examples/__init__.py", "examples/exp_configs/non_rl",
              "examples/exp_configs/templates"]  # fmt: skip
DELIBERATE = "deliberate"
OUT_OF_SCOPE = "out of scope"
_RING = ("flowrun's ring has no junction links (Flow's ring coordinates put a 0.1 m junction "
         "between edges); the ring's physics is fixed")  # fmt: skip
_SEEDED = "the env draws from its seeded np_random, Flow's test seeds Python's random"
_MISSING = ("a network parameter left out: Flow raises KeyError, flowrun fills Flow's default "
            "or names the missing key")  # fmt: skip
#: failures that are expected, by file (every test of it) or ``file.Class.test``: (kind, reason)
KNOWN: dict[str, tuple[str, str]] = {
    "test_aimsun_api": (OUT_OF_SCOPE, "Aimsun (commercial simulator): flow.utils.aimsun"),
    "test_aimsun_scripting_api": (OUT_OF_SCOPE, "Aimsun (commercial simulator)"),
    "test_examples": (
        OUT_OF_SCOPE,
        "imports Flow's examples/ train.py and RL configs (Ray 0.8's PPOTFPolicy, h-baselines, "
        "stable-baselines 2) and the Bay Bridge configs (networks downloaded at run time)",
    ),
    "test_controllers.TestFollowerStopper.test_find_intersection_dist": (DELIBERATE, _RING),
    "test_controllers.TestNonLocalFollowerStopper.test_find_intersection_dist": (
        DELIBERATE, _RING),
    "test_environments.TestBottleneckDesiredVelocityEnv.test_reset_inflows": (
        DELIBERATE, _SEEDED),
    "test_environments.TestBottleneckEnv.test_get_bottleneck_density": (
        DELIBERATE,
        "the bottleneck's edge starts are measured on SUMO 1.28's network (Flow's hard-coded "
        "ones put edge 4 at 425 m, inside edge 3), so the initial placement differs",
    ),
    "test_environments.TestMergePOEnv.test_observation_action_space": (
        DELIBERATE,
        "MergePOEnv declares [-1, 1] for its relative speeds, which go negative (Flow declares "
        "Box(0, 1))",
    ),
    "test_environments.TestMultiAgentWaveAttenuationPOEnv.test_reset": (DELIBERATE, _SEEDED),
    "test_environments.TestWaveAttenuationEnv.test_reset": (DELIBERATE, _SEEDED),
    "test_params.TestEnvParams.test_clip_actions": (
        DELIBERATE, "Gymnasium's five-value step"),
    "test_scenario_base_class.TestEvenStartPosInternalLinks.test_even_start_pos_internal": (
        DELIBERATE,
        "SUMO 1.28's junction links on the figure eight are longer than Flow's edge starts "
        "assume: uniform placement moves a car off a link to the next edge's start",
    ),
    "test_scenario_base_class.TestNetworkTemplateGenerator.test_network_template": (
        DELIBERATE,
        "SumoCarFollowingParams / SumoLaneChangeParams hold one typed attribute per parameter; "
        "their controller_params and modes equal Flow's, the test compares __dict__",
    ),
    "test_scenario_base_class.TestNextPrevEdge.test_next_prev_edge_ring_road": (
        DELIBERATE, _RING),
    "test_scenarios.TestBottleneckNetwork.test_additional_net_params": (DELIBERATE, _MISSING),
    "test_scenarios.TestFigureEightNetwork.test_additional_net_params": (DELIBERATE, _MISSING),
    "test_scenarios.TestHighwayNetwork.test_additional_net_params": (DELIBERATE, _MISSING),
    "test_scenarios.TestI210SubNetwork.test_additional_net_params": (DELIBERATE, _MISSING),
    "test_scenarios.TestMergeNetwork.test_additional_net_params": (DELIBERATE, _MISSING),
    "test_scenarios.TestMultiRingNetwork.test_additional_net_params": (DELIBERATE, _MISSING),
    "test_scenarios.TestRingNetwork.test_additional_net_params": (DELIBERATE, _MISSING),
    "test_scenarios.TestTrafficLightGridNetwork.test_additional_net_params": (
        DELIBERATE, _MISSING),
    "test_scenarios.TestI210SubNetwork.test_specify_routes": (
        DELIBERATE,
        "a network's routes are checked against its .net.xml when it is built (Flow: when "
        "SUMO starts); the test builds ghost-edge routes on test2.net.xml, which has no ghost0",
    ),
    "test_traffic_lights.TestCustomization.test_static_phases": (
        DELIBERATE,
        "every reset restarts SUMO (an episode depends only on its seed); Flow without "
        "restart_instance keeps the clock and signal programs running across resets",
    ),
    "test_vehicles.TestMultiLaneData.test_no_junctions_highway": (
        DELIBERATE,
        "SUMO 1.28's junction links: its highway links are 0.1 m long (flowrun: headway and "
        "tailway 20.1 m); Flow's expected 22.997 / 20.097 m hold its SUMO's links",
    ),
    "test_vehicles.TestMultiLaneData.test_no_junctions_ring": (DELIBERATE, _RING),
    "test_visualizers.TestPlotters.test_time_space_diagram_ring_road": (
        DELIBERATE,
        "positions from flowrun's ring edge starts, which have no 0.1 m junctions (Flow's "
        "emission file was written on Flow's ring)",
    ),
    "test_visualizers.TestPlotters.test_plot_ray_results": (
        DELIBERATE,
        "with no column named, Flow's plot_progress prints the file's columns to stdout; "
        "flowrun's raises an error listing them (library code does not print)",
    ),
    "test_visualizers.TestVisualizerRLlib": (
        OUT_OF_SCOPE,
        "Flow's test checkpoints are pickled Ray 0.8 TensorFlow policies; Ray 2.60's RLlib "
        "(PyTorch, no TensorFlow installed) cannot restore them",
    ),
}


@dataclass
class FileResult:
    """One test file's outcome."""

    name: str
    tests: int = 0
    passed: int = 0
    skipped: int = 0
    failures: dict[str, str] = field(default_factory=dict)  # test id -> last error line
    passed_ids: list[str] = field(default_factory=list)
    note: str = ""


def known_reason(test_id: str) -> tuple[str, str] | None:
    """The (kind, reason) of a known failure, by test id ``file.Class.test`` or by file."""
    parts = test_id.split(" ")[0].split(".")
    for n in range(len(parts), 0, -1):
        hit = KNOWN.get(".".join(parts[:n]))
        if hit is not None:
            return hit
    return None


# --------------------------------------------------------------------------- extracting Flow


def flow_tar(flow: Path, commit: str | None) -> bytes | None:
    """``git archive`` of Flow's tests and templates when ``flow`` is a git repository without a
    work tree holding them (a bare repository or ``--commit`` given); None for a plain checkout."""
    if (flow / "tests" / "fast_tests").is_dir() and commit is None:
        return None
    done = subprocess.run(
        ["git", "-C", str(flow), "archive", commit or "HEAD", *FLOW_PATHS],
        capture_output=True, check=False,
    )
    if done.returncode != 0:
        sys.exit(f"error: git archive in {flow} failed: {done.stderr.decode().strip()}")
    return done.stdout


def extract_flow(flow: Path, commit: str | None, dest: Path) -> None:
    """Flow's tests and templates into ``dest``, from a checkout or from git."""
    data = flow_tar(flow, commit)
    if data is None:
        for rel in FLOW_PATHS:
            if (flow / rel).is_dir():
                shutil.copytree(flow / rel, dest / rel, ignore=_NO_CACHE)
            elif (flow / rel).is_file():
                (dest / rel).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy(flow / rel, dest / rel)
        return
    with tarfile.open(fileobj=BytesIO(data)) as tar:
        tar.extractall(dest, filter="data")


_NO_CACHE = shutil.ignore_patterns("__pycache__")
IMPORT_REWRITES = [
    (re.compile(r"(?<![\w.])flow\.(?=\w)"), "flowrun."),  # flow.core..., __import__("flow.x")
    (re.compile(r"^(\s*)from flow import ", re.M), r"\1from flowrun import "),
    (re.compile(r"^(\s*)import flow$", re.M), r"\1import flowrun as flow"),
    (re.compile(r"(?<![\w.])gym\.spaces\b"), "gymnasium.spaces"),
    (re.compile(r"^(\s*)import gym$", re.M), r"\1import gymnasium as gym"),
]


def rewrite_imports(text: str) -> str:
    """Flow's module names as flowrun's, Gym's as Gymnasium's; nothing else changes."""
    for pattern, repl in IMPORT_REWRITES:
        text = pattern.sub(repl, text)
    return text


def prepare(flow: Path, commit: str | None, dest: Path) -> list[Path]:
    """The temporary checkout: Flow's tests (imports rewritten) and templates, flowrun's package
    and configs; returns the fast-test files."""
    extract_flow(flow, commit, dest)
    for py in [*(dest / "tests").rglob("*.py"), *(dest / "examples").rglob("*.py")]:
        py.write_text(rewrite_imports(py.read_text()))
    shutil.copytree(ROOT / "flowrun", dest / "flowrun", ignore=_NO_CACHE)
    (dest / "configs").symlink_to(ROOT / "configs")
    files = sorted((dest / "tests" / "fast_tests").glob("test_*.py"))
    if not files:
        sys.exit(f"error: no tests/fast_tests/test_*.py in {flow} (commit {commit or 'HEAD'})")
    return files


# --------------------------------------------------------------------------- running one file


class _Recorder(unittest.TextTestResult):
    """A result that appends one JSON line per finished test to a file (kept on a timeout)."""

    out: Path

    def _write(self, test: unittest.TestCase, outcome: str, detail: str = "") -> None:
        with self.out.open("a") as f:
            f.write(json.dumps({"id": test.id(), "outcome": outcome, "detail": detail}) + "\n")

    def addSuccess(self, test: unittest.TestCase) -> None:
        super().addSuccess(test)
        self._write(test, "passed")

    def addFailure(self, test, err) -> None:  # type: ignore[no-untyped-def]
        super().addFailure(test, err)
        self._write(test, "failed", "".join(traceback.format_exception(*err)))

    def addError(self, test, err) -> None:  # type: ignore[no-untyped-def]
        super().addError(test, err)
        self._write(test, "error", "".join(traceback.format_exception(*err)))

    def addSkip(self, test: unittest.TestCase, reason: str) -> None:
        super().addSkip(test, reason)
        self._write(test, "skipped", reason)

    def addExpectedFailure(self, test, err) -> None:  # type: ignore[no-untyped-def]
        super().addExpectedFailure(test, err)
        self._write(test, "passed")

    def addUnexpectedSuccess(self, test: unittest.TestCase) -> None:
        super().addUnexpectedSuccess(test)
        self._write(test, "failed", "unexpected success")


def run_one(module: str, out: Path) -> None:
    """In the child: load ``module`` and run its tests, one JSON line per test into ``out``."""
    here = str(Path(__file__).resolve().parent)
    sys.path[:] = [os.getcwd()] + [p for p in sys.path if p not in ("", here)]
    suite = unittest.defaultTestLoader.loadTestsFromName(module)
    count = suite.countTestCases()
    failed_import = any(
        t.__class__.__name__ == "_FailedTest" for t in _iter_tests(suite)
    )
    with out.open("w") as f:
        f.write(json.dumps({"count": count, "import_failed": failed_import}) + "\n")
    _Recorder.out = out
    runner = unittest.TextTestRunner(
        resultclass=_Recorder,  # type: ignore[arg-type]  # typeshed's generic result type
        verbosity=0,
        stream=sys.stderr,
    )
    runner.run(suite)


def _iter_tests(suite: unittest.TestSuite) -> list[unittest.TestCase]:
    tests: list[unittest.TestCase] = []
    for item in suite:
        if isinstance(item, unittest.TestSuite):
            tests.extend(_iter_tests(item))
        else:
            tests.append(item)
    return tests


def last_line(detail: str) -> str:
    """The error's last non-empty line (its type and message)."""
    lines = [ln.strip() for ln in detail.strip().splitlines() if ln.strip()]
    return lines[-1][:200] if lines else ""


def run_file(path: Path, tmp: Path, timeout: float) -> FileResult:
    """Run one Flow test file in a child process; the result, a failed import or a timeout
    counting every test not reported as failing."""
    result = FileResult(path.stem)
    n_src = len(re.findall(r"^\s+def test_", path.read_text(), re.M))
    out = tmp / f".{path.stem}.jsonl"
    env = {**os.environ, "PYTHONPATH": str(tmp), "MPLBACKEND": "Agg", "TEST_FLAG": "True"}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--run-one",
           f"tests.fast_tests.{path.stem}", "--results", str(out)]  # fmt: skip
    try:
        done = subprocess.run(cmd, cwd=tmp, env=env, capture_output=True, text=True,
                              timeout=timeout, check=False)
        stderr = done.stderr
    except subprocess.TimeoutExpired:
        stderr, result.note = "", f"timed out after {timeout:.0f} s"
    lines = [json.loads(ln) for ln in out.read_text().splitlines()] if out.exists() else []
    if not lines or lines[0].get("import_failed"):
        result.tests = n_src
        detail = lines[1]["detail"] if len(lines) > 1 else stderr
        result.failures = {f"{path.stem} (import)": last_line(detail)}
        result.note = result.note or "import failed: every test counted as failing"
        return result
    result.tests = lines[0]["count"]
    for row in lines[1:]:
        test_id = row["id"].removeprefix("tests.fast_tests.")
        if row["outcome"] == "passed":
            result.passed += 1
            result.passed_ids.append(test_id)
        elif row["outcome"] == "skipped":
            result.skipped += 1
        else:
            result.failures[test_id] = last_line(row["detail"])
    missing = result.tests - result.passed - result.skipped - len(result.failures)
    if missing > 0:
        result.failures[f"{path.stem} ({missing} not run)"] = result.note or last_line(stderr)
    return result


# --------------------------------------------------------------------------- the report


def failed_count(r: FileResult) -> int:
    """Failed or errored tests of a file (an import failure or timeout counts every test)."""
    return r.tests - r.passed - r.skipped


def known_count(r: FileResult) -> int:
    """How many of the file's failing tests are known (deliberate or out of scope)."""
    if not r.failures:
        return 0
    if KNOWN.get(r.name):
        return failed_count(r)
    return sum(1 for t in r.failures if known_reason(t) is not None)


def print_table(results: list[FileResult]) -> None:
    """The per-file table, the total, then every failure with its reason or its error."""
    head = (f"{'file':<32} {'tests':>5} {'passed':>6} {'failed':>6} {'skipped':>7} "
            f"{'known':>5}  note")  # fmt: skip
    print(head)
    print("─" * len(head))
    for r in results:
        print(f"{r.name:<32} {r.tests:>5} {r.passed:>6} {failed_count(r):>6} {r.skipped:>7} "
              f"{known_count(r):>5}  {r.note}")
    tests, passed = sum(r.tests for r in results), sum(r.passed for r in results)
    failed, known = sum(failed_count(r) for r in results), sum(known_count(r) for r in results)
    print("─" * len(head))
    print(f"{'total':<32} {tests:>5} {passed:>6} {failed:>6} "
          f"{sum(r.skipped for r in results):>7} {known:>5}")
    print(f"\n{passed} of {tests} passing; {known} failing known (deliberate or out of scope), "
          f"{failed - known} failing otherwise")
    for kind in (DELIBERATE, OUT_OF_SCOPE, None):
        rows = [(t, e) for r in results for t, e in r.failures.items()
                if (known_reason(t) or (None, ""))[0] == kind]
        if rows:
            print(f"\n{kind or 'not known'}:")
        for test_id, error in rows:
            hit = known_reason(test_id)
            print(f"  {test_id}: {hit[1] if hit else error}")
    stale = [t for r in results for t in r.passed_ids if known_reason(t) is not None]
    if stale:
        print("\nlisted as known failures but passing now (remove them from KNOWN):")
        for test_id in stale:
            print(f"  {test_id}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flow", type=Path, help="Flow's checkout, or its git directory")
    parser.add_argument("--commit", help="the commit to read from a git directory (default HEAD)")
    parser.add_argument("--only", nargs="*", default=[],
                        help="test files to run, e.g. test_vehicles")  # fmt: skip
    parser.add_argument("--timeout", type=float, default=1800, help="seconds per test file")
    parser.add_argument("--keep", type=Path, help="lay the folder out here and keep it")
    parser.add_argument("--json", type=Path, help="also write the results to this file")
    parser.add_argument("--run-one", help=argparse.SUPPRESS)
    parser.add_argument("--results", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.run_one:
        run_one(args.run_one, args.results)
        return
    if args.flow is None:
        parser.error("--flow is required")
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="flow-unit-") as scratch:
        tmp = args.keep or Path(scratch)
        if args.keep and args.keep.exists():
            parser.error(f"--keep {args.keep}: already exists; name a new folder")
        tmp.mkdir(parents=True, exist_ok=True)
        files = prepare(args.flow, args.commit, tmp)
        if args.only:
            wanted = {name.removesuffix(".py") for name in args.only}
            files = [f for f in files if f.stem in wanted]
        print(f"Flow's fast tests from {args.flow} ({args.commit or 'HEAD'}), flowrun from "
              f"{ROOT}; load average {os.getloadavg()[0]:.1f}", flush=True)
        results = []
        for path in files:
            results.append(run_file(path, tmp, args.timeout))
            print(f"  {path.stem}: {results[-1].passed}/{results[-1].tests}", flush=True)
    print()
    print_table(results)
    if args.json:
        args.json.write_text(json.dumps([r.__dict__ for r in results], indent=1))
    print(f"\n({time.monotonic() - start:.0f} s)")


if __name__ == "__main__":
    main()

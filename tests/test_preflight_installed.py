"""A recipe whose training library is not installed: one line at train.algorithm's file:line
with the package and its install command, exit 1, before any process or run folder exists.

"Not installed" is real here without uninstalling anything: each command runs in a child
Python whose ``sys.modules[name] = None`` makes ``import name`` raise ModuleNotFoundError.
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.config.yamlio import Locations
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config_located
from flowrun.preflight.installed import check_training_installed, training_library_problem
from flowrun.training import deps

ROOT = Path(__file__).resolve().parents[1]
FIGURE_EIGHT = ROOT / "configs/benchmarks/figureeight0.yaml"  # ARS


def algorithm_line(path: Path) -> int:
    """The line of ``train.algorithm`` in a shipped config."""
    lines = path.read_text().splitlines()
    return lines.index("train:") + 1 + next(
        i for i, text in enumerate(lines[lines.index("train:"):]) if text.startswith("  algorithm:")
    )


ALGORITHM_LINE = algorithm_line(FIGURE_EIGHT)
MERGE = ROOT / "configs/benchmarks/merge0.yaml"  # PPO
RLLIB = ROOT / "configs/rllib_ring.yaml"  # train.backend: rllib at line 40
TRAIN_HINT = "pip install torch==2.13.0 && pip install -e '.[train]'"

BLOCKED_CLI = """
import sys
for name in sys.argv[1].split(","):
    sys.modules[name] = None
from flowrun.cli.main import main
sys.argv = ["flowrun", *sys.argv[2:]]
main()
"""


def flowrun_without(blocked: str, *args: str | Path) -> subprocess.CompletedProcess[str]:
    """``flowrun ARGS`` in a child Python where the modules ``blocked`` cannot be imported."""
    cmd = [sys.executable, "-c", BLOCKED_CLI, blocked, *map(str, args)]
    return subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=300)


def trpo_config(tmp_path: Path) -> tuple[Path, int]:
    """figureeight0 with TRPO (sb3-contrib) instead of ARS, and the line of its algorithm."""
    path = tmp_path / "trpo.yaml"
    text = FIGURE_EIGHT.read_text().split("\ntrain:\n")[0]
    path.write_text(f"{text}\ntrain:\n  algorithm: TRPO\n  total_timesteps: 100\n")
    return path, text.count("\n") + 3


@pytest.mark.parametrize(
    ("blocked", "config", "line", "package"),
    [
        ("sb3_contrib", FIGURE_EIGHT, ALGORITHM_LINE, "sb3-contrib"),
        ("stable_baselines3", MERGE, algorithm_line(MERGE), "stable-baselines3"),
        ("torch", MERGE, algorithm_line(MERGE), "torch"),
    ],
)
def test_train_without_the_algorithm_library_is_one_located_line(
    tmp_path: Path, blocked: str, config: Path, line: int, package: str
) -> None:
    out = tmp_path / "runs"
    done = flowrun_without(blocked, "train", config, "--out", out)
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"error: {config}:{line}: train.algorithm:")
    assert f"needs {package} (module '{blocked}'), which is not installed" in lines[0]
    assert TRAIN_HINT in lines[0]
    assert "starting" not in done.stdout  # no "starting N environment process(es)"
    assert not out.exists()  # no run folder, no monitor files: nothing started


def test_trpo_without_sb3_contrib_names_the_installed_algorithms(tmp_path: Path) -> None:
    path, line = trpo_config(tmp_path)
    done = flowrun_without("sb3_contrib", "train", path, "--out", tmp_path / "runs")
    assert done.returncode == 1
    assert f"{path}:{line}: train.algorithm: TRPO needs sb3-contrib" in done.stderr
    assert "or use one that is installed: PPO, A2C, SAC, TD3, DDPG" in done.stderr
    assert not (tmp_path / "runs").exists()


def test_rllib_without_ray_is_located_at_train_backend(tmp_path: Path) -> None:
    done = flowrun_without("ray", "train", RLLIB, "--out", tmp_path / "runs")
    assert done.returncode == 1
    assert f"error: {RLLIB}:40: train.backend: RLlib needs ray[rllib]" in done.stderr
    assert "pip install torch==2.13.0 && pip install -e '.[rllib]'" in done.stderr
    assert "Ray" not in done.stdout and not (tmp_path / "runs").exists()


def test_benchmark_train_checks_every_recipe_before_any_baseline(tmp_path: Path) -> None:
    out = tmp_path / "out"
    done = flowrun_without("sb3_contrib", "benchmark", "figureeight0", "--train", "--out", out)
    assert done.returncode == 1
    assert f"{FIGURE_EIGHT}:{ALGORITHM_LINE}: train.algorithm: ARS needs sb3-contrib" in done.stderr
    assert not out.exists()  # no benchmark folder: no baseline ran


def test_validate_warns_and_accepts_the_config() -> None:
    done = flowrun_without("sb3_contrib", "validate", FIGURE_EIGHT)
    assert done.returncode == 0
    where = f"figureeight0.yaml:{ALGORITHM_LINE}"
    assert f"{where}: train.algorithm: ARS needs sb3-contrib" in done.stderr
    assert "the config is valid (baseline runs it), only train needs it" in done.stderr
    assert "algorithm: ARS" in done.stdout  # the resolved config is printed


def test_check_in_process_names_the_missing_module(monkeypatch: pytest.MonkeyPatch) -> None:
    real = deps.import_module

    def without_contrib(name: str) -> object:
        if name in ("sb3_contrib", "flowrun.training.ars"):
            raise ModuleNotFoundError("No module named 'sb3_contrib'", name="sb3_contrib")
        return real(name)

    cfg, loc = load_config_located(FIGURE_EIGHT, [])
    assert training_library_problem(cfg, loc) is None  # everything installed here
    monkeypatch.setattr(deps, "import_module", without_contrib)
    with pytest.raises(ConfigError) as err:
        check_training_installed(cfg, loc)
    assert err.value.location.endswith(f"figureeight0.yaml:{ALGORITHM_LINE}")
    assert err.value.path == "train.algorithm"
    cfg, loc = load_config_located(MERGE, [])
    check_training_installed(cfg, loc)  # PPO needs no sb3-contrib
    assert training_library_problem(replace(cfg, train=None), Locations("x.yaml")) is None


def test_benchmark_train_reports_a_recipe_typo_before_any_baseline(tmp_path: Path) -> None:
    configs = tmp_path / "configs"
    configs.mkdir()
    text = FIGURE_EIGHT.read_text()
    (configs / "figureeight0.yaml").write_text(text.replace("n_delta: ", "n_deltas: "))
    line = text[: text.index("n_delta: ")].count("\n") + 1
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["benchmark", "figureeight0", "--train", "--configs",
                                      str(configs), "--out", str(out)])  # fmt: skip
    assert result.exit_code == 1
    assert (f"{configs / 'figureeight0.yaml'}:{line}: train.hyperparams.n_deltas: ARS has no "
            "hyper-parameter 'n_deltas' (did you mean 'n_delta'?)") in result.stderr
    assert not out.exists()

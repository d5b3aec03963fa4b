"""Start-up: ``flowrun --help``/``--version``/``list`` import only what they need; the lazy
command group finds every command."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from flowrun import __version__
from flowrun.cli.main import COMMANDS, app, load_commands

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("matplotlib", "torch", "stable_baselines3", "libsumo", "flowrun.replay", "rich")


def modules_after(*argv: str) -> set[str]:
    """The modules imported by ``flowrun ARGV`` in a fresh interpreter."""
    code = (
        "import sys, json\n"
        "from flowrun.cli.main import main\n"
        f"sys.argv = ['flowrun', *{list(argv)!r}]\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "print(json.dumps(sorted(sys.modules)), file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    return set(json.loads(done.stderr.strip().splitlines()[-1]))


@pytest.mark.parametrize("argv", [("--help",), ("--version",), ("list", "controllers")])
def test_quick_commands_import_no_heavy_library(argv: tuple[str, ...]) -> None:
    loaded = modules_after(*argv)
    assert not [m for m in loaded if m.split(".")[0] in HEAVY or m in HEAVY]
    assert "flowrun.cli.commands_run" not in loaded


def test_list_envs_imports_no_env_class_nor_the_kernel() -> None:
    loaded = modules_after("list", "envs")
    assert "flowrun.kernel" not in loaded
    assert "flowrun.envs.base" not in loaded
    assert "flowrun.recording" not in loaded


def test_validate_without_train_imports_no_kernel_nor_recording() -> None:
    loaded = modules_after("validate", "configs/sugiyama.yaml")
    assert "flowrun.envs.base" in loaded  # the env class is checked ...
    assert "flowrun.kernel.kernel" not in loaded  # ... without the kernel it runs on
    assert "flowrun.recording" not in loaded
    assert "flowrun.envs.frames" not in loaded


def test_env_names_are_the_classes_names() -> None:
    from flowrun.envs.registry import ALIAS_NAMES, ENV_NAMES, env_classes, resolve_env_class

    assert [c.__name__ for c in env_classes()] == list(ENV_NAMES)
    assert [resolve_env_class(name) for name in ENV_NAMES] == list(env_classes())
    for alias, name in ALIAS_NAMES.items():
        assert resolve_env_class(alias).__name__ == name


def test_version_prints_the_package_version() -> None:
    result = CliRunner().invoke(app, ["--version"])
    assert result.exit_code == 0
    assert result.output == f"flowrun {__version__}\n"


def test_help_lists_every_command_with_its_line() -> None:
    result = CliRunner().invoke(app, ["--help"], terminal_width=80)
    assert result.exit_code == 0
    for name, (_, line) in COMMANDS.items():
        assert f"{name}  " in result.output and line in result.output
    assert max(len(row) for row in result.output.splitlines()) <= 80


def test_every_listed_command_is_registered_by_its_module() -> None:
    for name, (module, _) in COMMANDS.items():
        assert name in load_commands(module), f"{module} does not register {name}"


def test_a_command_runs_through_the_lazy_group() -> None:
    group = typer.main.get_command(app)
    assert list(group.commands) == list(COMMANDS)  # type: ignore[attr-defined]
    result = CliRunner().invoke(app, ["list", "controllers"])
    assert result.exit_code == 0
    assert "IDM" in result.output.split()


def test_unknown_command_is_refused_with_a_suggestion() -> None:
    result = CliRunner().invoke(app, ["baselin"])
    assert result.exit_code == 2
    assert "baseline" in result.output


def modules_after_import(module: str) -> set[str]:
    """The modules imported by ``import MODULE`` in a fresh interpreter."""
    code = f"import sys, json, {module}\nprint(json.dumps(sorted(sys.modules)))\n"
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    return set(json.loads(done.stdout))


TRAINING_HEAVY = (
    "flowrun.training.trainer",
    "flowrun.training.evaluate",
    "flowrun.kernel",
    "flowrun.envs",
    "flowrun.recording",
    "torch",
    "stable_baselines3",
    "libsumo",
)
LIGHT_TRAINING = (
    "flowrun.training.deps",
    "flowrun.training.algorithms",
    "flowrun.training.rllib.deps",
)


@pytest.mark.parametrize("module", LIGHT_TRAINING)
def test_light_training_modules_import_no_trainer_nor_kernel(module: str) -> None:
    loaded = modules_after_import(module)
    assert module in loaded
    assert not [m for m in loaded if any(m == h or m.startswith(h + ".") for h in TRAINING_HEAVY)]


def test_training_package_names_load_on_first_use() -> None:
    import flowrun.training as training
    from flowrun.training.evaluate import eval_config  # binds the submodule on the package ...

    assert callable(eval_config)
    assert training.evaluate.__name__ == "evaluate"  # ... yet the name stays the function
    assert training.train.__module__ == "flowrun.training.trainer"
    assert training.all_human is sys.modules["flowrun.training.evaluate"].all_human
    assert sorted(training.__all__) == sorted(set(training.__all__) & set(dir(training)))
    with pytest.raises(AttributeError, match="no attribute 'trainer_of_nothing'"):
        training.trainer_of_nothing  # noqa: B018

"""``baseline`` and ``train`` refuse a bad ``env.class`` as ``validate`` does: one line with
``file:line``, the key path and the fix, exit 1, and no run folder."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app

ROOT = Path(__file__).resolve().parent.parent
CASES = [
    ("NoSuchEnv", "env.class: unknown environment 'NoSuchEnv'"),
    ("my_missing_module:Missing", "env.class: cannot import module 'my_missing_module'"),
    ("os:path", "env.class: 'os:path' is not a subclass of flowrun.envs.Env"),
    ("WaveAttenuationPOEnvv", "did you mean 'WaveAttenuationPOEnv'"),
]


def with_env_class(tmp_path: Path, shipped: str, env_class: str) -> tuple[Path, int]:
    """A copy of ``configs/<shipped>`` naming ``env_class``; the line of ``class:``."""
    lines = (ROOT / "configs" / shipped).read_text().splitlines()
    at = next(i for i, ln in enumerate(lines) if ln.startswith("  class:"))
    lines[at] = f"  class: {env_class}"
    path = tmp_path / "exp.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path, at + 1


def one_error(args: list[str]) -> str:
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0]


@pytest.mark.parametrize(("env_class", "message"), CASES)
@pytest.mark.parametrize(
    ("command", "shipped"), [("baseline", "sugiyama.yaml"), ("train", "ring_wave.yaml")]
)
def test_bad_env_class_is_refused_at_its_line(
    tmp_path: Path, command: str, shipped: str, env_class: str, message: str
) -> None:
    config, line = with_env_class(tmp_path, shipped, env_class)
    out = tmp_path / "runs"
    error = one_error([command, str(config), "--out", str(out)])
    assert error.startswith(f"error: {config}:{line}: env.class: "), error
    assert message in error
    assert error == one_error(["validate", str(config)])  # word for word
    assert not out.exists()


def test_bad_env_class_from_set_names_the_option(tmp_path: Path) -> None:
    out = tmp_path / "runs"
    config = ROOT / "configs" / "sugiyama.yaml"
    error = one_error(["baseline", str(config), "--set", "env.class=NoSuchEnv", "--out", str(out)])
    assert error.startswith("error: --set: env.class: unknown environment 'NoSuchEnv'"), error
    assert not out.exists()

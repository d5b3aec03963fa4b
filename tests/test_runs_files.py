"""Run folders under hostile conditions: ``--out`` a file, read-only, on a full disk; two runs
in the same second; config names with path characters; runs that fail. Real SUMO, real file
systems (a small tmpfs when this user may mount one, else a file-size limit), no mocks."""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.errors import ConfigError, RecordingError
from flowrun.experiment.baseline import run_baseline
from flowrun.loading.loader import load_config
from flowrun.recording.reader import open_log
from flowrun.rundir.folders import is_complete, read_status

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parent.parent
SUGIYAMA = ROOT / "configs" / "sugiyama.yaml"
FLOWRUN = Path(sys.executable).parent / "flowrun"


def tree(path: Path) -> list[str]:
    return sorted(str(p.relative_to(path)) for p in path.rglob("*"))


def one_line_error(result: Any, needle: str) -> None:
    assert result.exit_code == 1, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    assert needle in lines[0], lines[0]
    assert "Traceback" not in result.stderr


def baseline(*args: str) -> Any:
    return CliRunner().invoke(app, ["baseline", str(SUGIYAMA), *args])


@contextmanager
def tmpfs(path: Path, options: str) -> Iterator[Path]:
    """A real tmpfs at ``path`` (skips the test when this user may not mount one)."""
    path.mkdir()
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)],
        capture_output=True,
        check=False,
    )
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


# --- --out -----------------------------------------------------------------------------------


@pytest.mark.parametrize("below", ["", "sub"])
def test_out_that_is_a_file_is_one_clear_error_and_the_file_is_untouched(
    tmp_path: Path, below: str
) -> None:
    file = tmp_path / "results"
    file.write_text("my notes\n")
    result = baseline("--out", str(file / below) if below else str(file), "--steps", "5")
    one_line_error(result, "is a file")
    assert file.read_text() == "my notes\n"
    assert tree(tmp_path) == ["results"]


def test_read_only_out_is_one_clear_error(tmp_path: Path) -> None:
    if os.geteuid() == 0:  # root writes through permissions: use a read-only file system
        with tmpfs(tmp_path / "ro", "size=64k,ro") as ro:
            result = baseline("--out", str(ro / "runs"), "--steps", "5")
            one_line_error(result, "read-only")
            assert tree(ro) == []
        return
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        result = baseline("--out", str(ro), "--steps", "5")
        one_line_error(result, "cannot write")
        assert tree(ro) == []
    finally:
        ro.chmod(0o755)


def check_disk_full_run(out: Path, proc: subprocess.CompletedProcess[str], why: str) -> None:
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr  # one line: no chain of tracebacks
    assert lines[0].startswith("error: cannot write run folder")
    assert why in lines[0]
    (folder,) = out.glob("sugiyama/*")
    status = read_status(folder)
    assert status.state == "failed"
    assert status.error is not None and why in status.error
    assert not is_complete(folder)
    metrics = folder / "metrics.json"  # never left saying "running" next to a failed status
    assert not metrics.exists() or json.loads(metrics.read_text())["status"] == "failed"
    try:  # what reached the disk is readable, or refused in one clear error
        steps = [f.step for f in open_log(folder / "run_0.mcap").frames()]
        assert steps == list(range(len(steps)))
    except RecordingError as err:
        assert str(err)


def test_full_disk_fails_in_one_line_and_labels_the_run_failed(tmp_path: Path) -> None:
    with tmpfs(tmp_path / "small", "size=128k") as disk:
        proc = subprocess.run(
            [str(FLOWRUN), "baseline", str(SUGIYAMA), "--out", str(disk), "--steps", "10000"],
            capture_output=True,
            text=True,
            check=False,
        )
        check_disk_full_run(disk, proc, "disk full")


def test_file_size_limit_fails_in_one_line_and_labels_the_run_failed(tmp_path: Path) -> None:
    def limit() -> None:  # in the child: files may not grow past 120 kB (EFBIG, like a full disk)
        resource.setrlimit(resource.RLIMIT_FSIZE, (120_000, 120_000))

    proc = subprocess.run(
        [str(FLOWRUN), "baseline", str(SUGIYAMA), "--out", str(tmp_path), "--steps", "10000"],
        capture_output=True,
        text=True,
        check=False,
        preexec_fn=limit,
    )
    check_disk_full_run(tmp_path, proc, "file too large")


# --- same second, same seed, same folder -------------------------------------------------------


def test_a_run_never_overwrites_a_folder_of_the_same_second_and_seed(tmp_path: Path) -> None:
    # Folders named as this second's (and the next seconds') run would be, each with a file.
    now = datetime.now(UTC)
    taken = []
    for s in range(10):
        name = (now + timedelta(seconds=s)).strftime("%Y%m%d-%H%M%S") + "-0"
        folder = tmp_path / "sugiyama" / name
        folder.mkdir(parents=True)
        (folder / "mine.txt").write_text(name)
        taken.append(folder)
    result = baseline("--out", str(tmp_path), "--steps", "5")
    assert result.exit_code == 0, result.stderr
    for folder in taken:
        assert tree(folder) == ["mine.txt"]
        assert (folder / "mine.txt").read_text() == folder.name
    (new,) = set(tmp_path.glob("sugiyama/*")) - set(taken)
    assert new.name.endswith("-0-1")  # <timestamp>-<seed>-<n>
    assert is_complete(new)


def test_two_processes_started_together_write_two_folders_with_the_same_results(
    tmp_path: Path,
) -> None:
    cmd = [str(FLOWRUN), "baseline", str(SUGIYAMA), "--out", str(tmp_path), "--steps", "20"]
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]  # fmt: skip
    for proc in procs:
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err
    folders = sorted(tmp_path.glob("sugiyama/*"))
    assert len(folders) == 2
    assert all(is_complete(f) for f in folders)
    assert {read_status(f).pid for f in folders} == {p.pid for p in procs}
    metrics = [(f / "metrics.json").read_text() for f in folders]
    assert metrics[0] == metrics[1]  # same seed, separate processes: byte-identical
    assert json.loads(metrics[0])["status"] == "complete"


# --- names with path characters ------------------------------------------------------------------


@pytest.mark.parametrize("name", ["../escape", "a/b", "..", "/abs"])
def test_a_config_name_with_path_characters_writes_nothing_anywhere(
    tmp_path: Path, name: str
) -> None:
    work = tmp_path / "work"
    work.mkdir()
    config = work / "x.yaml"
    config.write_text(SUGIYAMA.read_text().replace("name: sugiyama", f"name: {json.dumps(name)}"))
    result = CliRunner().invoke(app, ["baseline", str(config), "--out", str(work / "runs")])
    one_line_error(result, "name")
    assert tree(tmp_path) == ["work", "work/x.yaml"]
    # The library refuses it too (a config built in Python is not checked by the loader).
    cfg = replace(load_config(SUGIYAMA), name=name)
    with pytest.raises(ConfigError, match="name"):
        run_baseline(cfg, steps=5, out=work / "runs")
    assert tree(tmp_path) == ["work", "work/x.yaml"]


# --- runs that fail ------------------------------------------------------------------------------

ENVS = '''
from flowrun.envs.ring.accel import AccelEnv
from flowrun.errors import ConfigError, SimulationError


class RefusingEnv(AccelEnv):
    def __init__(self, *args, **kwargs):
        raise ConfigError("RefusingEnv refuses these parameters")


class BreakingEnv(AccelEnv):
    def additional_command(self):
        if self.step_counter >= 30:
            raise SimulationError("the simulation broke at step 30")
'''


#: The user's module (a name no other test uses: imported modules stay in ``sys.modules``).
ENV_MODULE = "runs_files_user_envs"


@pytest.fixture
def user_env_config(tmp_path: Path) -> Iterator[Callable[[str], Path]]:
    """Writes the user's module and a config naming one of its classes; forgets the module."""

    def make(cls: str) -> Path:
        (tmp_path / f"{ENV_MODULE}.py").write_text(ENVS)
        config = tmp_path / f"{cls}.yaml"
        config.write_text(
            SUGIYAMA.read_text().replace("class: AccelEnv", f"class: {ENV_MODULE}:{cls}")
        )
        return config

    yield make
    sys.modules.pop(ENV_MODULE, None)


def test_a_run_failing_before_it_wrote_anything_leaves_no_folder(
    tmp_path: Path, user_env_config: Callable[[str], Path]
) -> None:
    config = user_env_config("RefusingEnv")
    result = CliRunner().invoke(app, ["baseline", str(config), "--out", str(tmp_path / "runs")])
    one_line_error(result, "RefusingEnv refuses")
    assert list((tmp_path / "runs").rglob("*")) == []


def test_a_run_failing_midway_keeps_its_log_and_says_failed(
    tmp_path: Path, user_env_config: Callable[[str], Path]
) -> None:
    config = user_env_config("BreakingEnv")
    out = tmp_path / "runs"
    result = CliRunner().invoke(app, ["baseline", str(config), "--out", str(out)])
    one_line_error(result, "broke at step 30")
    (folder,) = out.glob("sugiyama/*")
    status = read_status(folder)
    assert status.state == "failed"
    assert status.error is not None and "broke at step 30" in status.error
    m = json.loads((folder / "metrics.json").read_text())
    assert m["status"] == "failed" and m["partial"] is True
    frames = list(open_log(folder / "run_0.mcap").frames())
    assert [f.step for f in frames] == list(range(m["runs"][0]["steps"]))

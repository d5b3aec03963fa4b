"""One meaning for ``--out`` (a folder that receives the command's new outputs), ``--seed`` and
``--set`` wherever a simulation or a config is made, and nothing overwritten by ``replay``
or ``convert``."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
import typer
import yaml
from typer.testing import CliRunner, Result

from flowrun.cli.common import NO_SEED_OR_SET, OUT_HELP
from flowrun.cli.main import app
from flowrun.loading.loader import load_config
from flowrun.recording import McapRecorder
from flowrun.recording.synthetic import ring_frames
from tests.test_flow_params import RING_MODULE, write_module

#: Every command that writes something takes ``--out``.
WRITING = ("baseline", "train", "eval", "sweep", "replay", "convert")
#: Commands that make a config to run or write it: ``--seed`` and ``--set`` mean the same.
CONFIGURING = ("baseline", "train", "eval", "sweep", "convert")


def flowrun(*args: object) -> Result:
    return CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "200"})


def option(name: str, flag: str) -> Any:
    command = typer.main.get_command(app).commands[name]  # type: ignore[attr-defined]
    return next((p for p in command.params if flag in getattr(p, "opts", ())), None)


def record(path: Path, steps: int = 50) -> Path:
    meta = {"config_name": "ring", "seed": "0", "flowrun_version": "0.1.0"}
    with McapRecorder(path, metadata=meta, attachments={}) as rec:
        for frame, stats in ring_frames(22, steps):
            rec.write(frame, stats)
    return path


@pytest.mark.parametrize("name", WRITING)
def test_out_is_a_folder_that_receives_new_outputs_on_every_command(name: str) -> None:
    opt = option(name, "--out")
    assert opt is not None and not opt.hidden
    assert opt.help.startswith(OUT_HELP), (name, opt.help)
    assert "nothing in it is overwritten" in opt.help


@pytest.mark.parametrize("flag", ["--seed", "--set"])
def test_seed_and_set_mean_the_same_wherever_a_config_is_made(flag: str) -> None:
    helps = {name: option(name, flag).help for name in CONFIGURING}
    assert len(set(helps.values())) == 1, helps


def test_replay_says_why_it_takes_no_seed_or_set() -> None:
    assert option("replay", "--seed") is None and option("replay", "--set") is None
    text = " ".join(flowrun("replay", "--help").stdout.split())
    assert NO_SEED_OR_SET in text


def test_replay_plot_never_overwrites_a_png(tmp_path: Path) -> None:
    log = record(tmp_path / "ring.mcap")
    first = flowrun("replay", log, "--plot", "speed")
    assert first.exit_code == 0, first.output
    (folder,) = (tmp_path / "replay").iterdir()  # default OUT: <log folder>/replay
    assert folder.name.startswith("ring-")
    png = folder / "speeds.png"
    before = png.read_bytes()
    png.write_bytes(b"mine")  # the user's own file under that name
    again = flowrun("replay", log, "--plot", "speed")
    assert again.exit_code == 0, again.output
    folders = sorted((tmp_path / "replay").iterdir())
    assert len(folders) == 2 and png.read_bytes() == b"mine"
    (new,) = (f for f in folders if f != folder)
    assert new.name.startswith("ring-")
    assert (new / "speeds.png").read_bytes()[:4] == before[:4] == b"\x89PNG"
    assert f"wrote {new / 'speeds.png'}" in again.stdout


def test_replay_out_receives_a_new_folder_and_leaves_the_rest_alone(tmp_path: Path) -> None:
    log = record(tmp_path / "ring.mcap")
    out = tmp_path / "plots"
    out.mkdir()
    (out / "speeds.png").write_bytes(b"older")
    result = flowrun("replay", log, "--plot", "speed", "--out", out)
    assert result.exit_code == 0, result.output
    assert (out / "speeds.png").read_bytes() == b"older"
    (made,) = out.glob("ring-*/speeds.png")
    assert made.stat().st_size > 1000
    assert not (tmp_path / "replay").exists()  # nothing in the default place


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--out", "{tmp}/plots"], "--out receives the plots of --plot"),
        (["--plot", "speed", "--out", "{log}"], "is a file; give a folder"),
    ],
)
def test_replay_out_without_plot_or_onto_a_file_is_one_line_error(
    tmp_path: Path, extra: list[str], message: str
) -> None:
    log = record(tmp_path / "ring.mcap")
    args = [a.format(tmp=tmp_path, log=log) for a in extra]
    result = flowrun("replay", log, *args)
    assert result.exit_code == 1
    assert message in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ring.mcap"]


def test_convert_out_folder_receives_module_yaml_with_set_and_seed(tmp_path: Path) -> None:
    module = write_module(tmp_path, "ring_hardening_convert", RING_MODULE)
    out = tmp_path / "converted"
    args = ["--set", "env.horizon=77", "--seed", "9", "--out", out]
    result = flowrun("convert", module, *args)
    assert result.exit_code == 0, result.output
    written = out / "ring_hardening_convert.yaml"
    cfg = load_config(written)
    assert (cfg.env.horizon, cfg.sim.seed) == (77, 9)
    assert "# with --set env.horizon=77 --set sim.seed=9" in written.read_text()
    again = flowrun("convert", module, "--out", out)
    assert again.exit_code == 1 and "exists already" in again.stderr
    assert load_config(written).env.horizon == 77  # untouched


def test_convert_out_still_takes_a_yaml_file_name_and_refuses_other_files(
    tmp_path: Path,
) -> None:
    module = write_module(tmp_path, "ring_hardening_file", RING_MODULE)
    target = tmp_path / "mine.yml"
    assert flowrun("convert", module, "--out", target).exit_code == 0
    assert yaml.safe_load(target.read_text())["env"]["class"] == "AccelEnv"
    notes = tmp_path / "notes.txt"
    notes.write_text("keep")
    refused = flowrun("convert", module, "--out", notes)
    assert refused.exit_code == 1
    assert "--out names a folder" in refused.stderr and notes.read_text() == "keep"


def test_convert_set_of_an_unknown_key_names_it(tmp_path: Path) -> None:
    module = write_module(tmp_path, "ring_hardening_badset", RING_MODULE)
    result = flowrun("convert", module, "--set", "env.horizonn=5")
    assert result.exit_code == 1
    assert "env.horizonn" in result.stderr and "horizon" in result.stderr


def test_replay_default_out_blocked_by_a_file_says_so(tmp_path: Path) -> None:
    log = record(tmp_path / "ring.mcap")
    (tmp_path / "replay").write_text("not a folder")
    result = flowrun("replay", log, "--plot", "speed")
    assert result.exit_code == 1
    assert result.stderr == (
        f"error: {tmp_path / 'replay'} (the default --out) is a file; give a folder for the "
        "plots (--out DIR)\n"
    )
    assert (tmp_path / "replay").read_text() == "not a folder"


def test_no_help_text_holds_brackets_that_rich_would_swallow() -> None:
    # typer renders help as rich markup: "[default: RUN_DIR/eval]" vanished from --help
    swallowed = re.compile(r"\[[A-Za-z/$]")
    commands = typer.main.get_command(app).commands  # type: ignore[attr-defined]
    for name, command in commands.items():
        texts = [command.help or ""] + [getattr(p, "help", None) or "" for p in command.params]
        for text in texts:
            assert not swallowed.search(text), (name, text)
    shown = " ".join(flowrun("eval", "--help").stdout.split())
    assert "(default OUT: RUN_DIR/eval)" in shown

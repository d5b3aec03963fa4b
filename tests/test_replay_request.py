"""A replay request is checked and its steps selected without the command line."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from flowrun.cli.main import app
from flowrun.errors import RecordingError
from flowrun.replay.request import ReplayRequest, select

SUGIYAMA = Path(__file__).resolve().parent.parent / "configs" / "sugiyama.yaml"


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("runs")
    result = CliRunner().invoke(app, ["baseline", str(SUGIYAMA), "--steps", "50", "--out",
                                      str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    (path,) = out.glob("sugiyama/*/run_0.mcap")
    return path


@pytest.mark.parametrize(
    ("request_", "needle"),
    [
        (ReplayRequest([]), "one log or two"),
        (ReplayRequest([Path("a"), Path("b")], csv=Path("x.csv")), "work on one log"),
        (ReplayRequest([Path("a")], start=5.0, end=1.0), "before --from"),
        (ReplayRequest([Path("a")], out=Path("plots")), "add --plot"),
        (ReplayRequest([Path("a")], vehicles=" , "), "--vehicles needs"),
    ],
)
def test_check_refuses_before_reading_anything(request_: ReplayRequest, needle: str) -> None:
    with pytest.raises(RecordingError, match=needle):
        request_.check()


def test_an_existing_output_is_refused(tmp_path: Path) -> None:
    taken = tmp_path / "e.csv"
    taken.write_text("mine")
    with pytest.raises(RecordingError, match="exists"):
        ReplayRequest([Path("a")], csv=taken).check()
    assert taken.read_text() == "mine"


@pytest.mark.sumo
def test_select_reads_the_window_and_the_vehicles(log: Path) -> None:
    chosen = select(ReplayRequest([log], start=1.0, end=3.0, vehicles="idm_0,ghost"))
    (series,) = chosen.series
    assert series.times.min() >= 1.0 and series.times.max() <= 3.0
    assert chosen.vehicles == ["idm_0", "ghost"] and chosen.missing == ["ghost"]
    assert chosen.summaries[0].first_time >= 1.0 and chosen.summaries[0].last_time <= 3.0
    with pytest.raises(RecordingError, match="no logged step within --from 900 s"):
        select(ReplayRequest([log], start=900.0))


@pytest.mark.sumo
def test_an_all_human_rollouts_return_reads_n_a(log: Path) -> None:
    from rich.console import Console

    from flowrun.cli.commands_replay import summary_table

    policy = select(ReplayRequest([log, log]))
    human = policy.logs[1]
    human.all_metadata = {**human.all_metadata,
                          "flowrun": {**human.metadata, "evaluation": "baseline"}}  # fmt: skip
    console = Console(width=120, record=True)
    console.print(summary_table([log, log], policy))
    (row,) = [line for line in console.export_text().splitlines() if "│ return" in line]
    cells = [c.strip() for c in row.split("│") if c.strip()]
    assert cells[0] == "return" and cells[2:] == ["n/a", "n/a"] and cells[1] != "n/a"

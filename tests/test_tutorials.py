"""The tutorial notebooks in docs/tutorials run from top to bottom (real SUMO, short seeded
runs) and say what the tutorials index says they do."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

TUTORIALS = Path(__file__).resolve().parent.parent / "docs" / "tutorials"
NOTEBOOKS = sorted(TUTORIALS.glob("*.ipynb"))
NEEDS = {"04_training": "stable_baselines3", "06_multiagent": "pettingzoo"}


def test_the_index_links_every_notebook() -> None:
    linked = set(re.findall(r"\(([0-9]{2}_\w+\.ipynb)\)", (TUTORIALS / "index.md").read_text()))
    assert linked == {p.name for p in NOTEBOOKS}
    assert len(NOTEBOOKS) == 6


@pytest.mark.sumo
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path: Path) -> None:
    if path.stem in NEEDS:
        pytest.importorskip(NEEDS[path.stem])
    nb = nbformat.read(path, as_version=4)
    assert not any(c.get("outputs") for c in nb.cells if c.cell_type == "code"), (
        f"{path.name} is committed with outputs; clear them"
    )
    client = nbclient.NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(TUTORIALS)}}
    )
    client.execute()
    errors = [
        out for cell in nb.cells for out in cell.get("outputs", []) if out.output_type == "error"
    ]
    assert not errors

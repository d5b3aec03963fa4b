"""The complete configs the README and docs/ show (a ```yaml block that starts with ``name:``)
pass ``flowrun validate``: a reader copies them first."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from flowrun.preflight.checks import validate_config

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"^```yaml\n(name:.*?)^```", re.S | re.M)


def shown_configs() -> list[tuple[str, str]]:
    """``(page:line, text)`` of every complete config block in the pages."""
    found = []
    for page in PAGES:
        text = page.read_text()
        for match in BLOCK.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            found.append((f"{page.name}:{line}", match.group(1)))
    return found


CONFIGS = shown_configs()


def test_the_readme_and_the_config_page_show_a_complete_config() -> None:
    pages = {where.split(":")[0] for where, _ in CONFIGS}
    assert {"README.md", "config.md"} <= pages


@pytest.mark.parametrize(("where", "text"), CONFIGS, ids=[w for w, _ in CONFIGS])
def test_a_config_shown_in_the_docs_validates(where: str, text: str, tmp_path: Path) -> None:
    file = tmp_path / "shown.yaml"
    file.write_text(text)
    cfg = validate_config(file)
    assert cfg.name and cfg.vehicles, where

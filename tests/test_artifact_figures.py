"""Every ``docs/*.png`` is either drawn from committed artifacts or a named screenshot, and
each artifact figure redraws from its artifacts alone."""

from __future__ import annotations

from pathlib import Path

import pytest

from scenarios.artifacts import ROOT, artifact_names
from scenarios.artifacts.figures import FIGURES, SCREENSHOTS

DOCS = ROOT / "docs"


def test_every_docs_figure_is_accounted_for():
    known = {f.path for f in FIGURES} | {s.path for s in SCREENSHOTS}
    pngs = {p.relative_to(ROOT).as_posix() for p in DOCS.glob("*.png")}
    assert pngs - known == set(), "a docs figure with no artifact or screenshot entry"
    assert known - pngs == set(), "an entry for a figure that is not in docs/"


def test_figures_name_committed_artifacts():
    names = set(artifact_names())
    for fig in FIGURES:
        assert set(fig.artifacts) <= names, fig.path


@pytest.mark.parametrize("fig", FIGURES, ids=lambda f: Path(f.path).name)
def test_each_figure_redraws_from_its_artifacts(fig, tmp_path):
    out = tmp_path / Path(fig.path).name
    fig.draw(out)
    assert out.stat().st_size > 5000
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_each_figure_is_shown_with_the_command_beside_it():
    """A page showing a figure says, next to it, how it is regenerated."""
    pages = [ROOT / "README.md", *DOCS.glob("*.md")]
    for fig in FIGURES:
        name = Path(fig.path).name
        showing = [p for p in pages if f"{name})" in p.read_text(encoding="utf-8")]
        assert showing, f"{fig.path} is shown nowhere"
        for page in showing:
            text = page.read_text(encoding="utf-8")
            at = text.index(f"{name})")
            near = text[max(0, at - 1500): at + 800]
            assert "rnhql report --figures" in near or any(
                a in near for a in fig.artifacts), f"{page.name}: {name} without its command"

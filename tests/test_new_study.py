"""Adding a study with a table in the docs touches three places, nothing else: the study's
script (it measures, then writes its artifact), a renderer of the artifact's kind in
``scenarios/artifacts/tables.py``, and a Cog block in the page that shows the table. A
throwaway study does the three here, end to end through Cog, and its table says when its
script changed (docs/architecture.md, "How to add").
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest

from scenarios import artifacts
from scenarios.artifacts import tables as artifact_tables

STUDY = '''\
"""A throwaway study: the mean of three seeds' numbers."""

import sys

from scenarios.artifacts import write_artifact


def main(out: str) -> None:
    values = [seed * 2.0 for seed in range(3)]
    write_artifact("demo-mean.three", "python -m demo --artifact three", ["grid"],
                   {"mean": sum(values) / len(values), "seeds": len(values)},
                   directory=__import__("pathlib").Path(out), study=__file__)


main(sys.argv[1])
'''

PAGE = """\
# Demo

<!-- [[[cog from scenarios.artifacts import render; render("demo-mean.three") ]]] -->
<!-- [[[end]]] -->
"""


@pytest.fixture
def demo_kind(monkeypatch, tmp_path):
    """The renderer a new study adds to scenarios/artifacts/tables.py, and docs/results in
    tmp_path."""
    monkeypatch.setitem(artifact_tables.KINDS, "demo-mean", None)  # restored afterwards

    @artifact_tables.renderer("demo-mean")
    def demo_mean(d):
        return f"| seeds | mean |\n|---|---|\n| {d['seeds']} | {d['mean']:.1f} |\n"

    results = tmp_path / "results"
    load = artifacts.load_artifact
    monkeypatch.setattr(artifacts, "load_artifact", lambda n, directory=results: load(n, directory))
    return results


def test_a_new_study_is_a_script_a_renderer_and_a_cog_block(demo_kind, tmp_path):
    import runpy
    import sys

    from cogapp import Cog

    script = tmp_path / "demo_study.py"
    script.write_text(STUDY)
    argv = sys.argv
    try:
        sys.argv = [str(script), str(demo_kind)]
        runpy.run_path(str(script), run_name="__main__")
    finally:
        sys.argv = argv
    doc = json.loads((demo_kind / "demo-mean.three.json").read_text())
    assert doc["data"] == {"mean": 2.0, "seeds": 3} and doc["study"]["code_sha256"]

    page = tmp_path / "demo.md"
    page.write_text(PAGE)
    assert Cog().main(["cog", "-r", "-I", str(Path(artifacts.ROOT)), str(page)]) == 0
    text = page.read_text()
    assert "| 3 | 2.0 |" in text and "python -m demo --artifact three" in text
    assert "**Stale**" not in text

    script.write_text(STUDY.replace("seed * 2.0", "seed * 3.0"))  # the study's code changed
    page.write_text(PAGE)
    Cog().main(["cog", "-r", "-I", str(Path(artifacts.ROOT)), str(page)])
    assert "**Stale**" in page.read_text() and "the study" in page.read_text()
    script.write_text(textwrap.dedent(STUDY).replace('"""A throwaway study',
                                                     '"""A reworded study'))
    assert artifacts.stale_parts(doc) == []  # a docstring is not what it measures

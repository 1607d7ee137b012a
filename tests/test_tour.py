"""The docs' short tour against a non-editable copy of the package (what ``pip install .``
gives a user: no docs/, no tests/, no checkout around it). The lines that compile nothing run
by default; the whole tour, with its learning runs, is slow."""

from __future__ import annotations

from pathlib import Path

import pytest

from scenarios.studies import tour


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    return tour.installed_copy(tmp_path_factory.mktemp("installed") / "site")


def _lines(commands: set[str]) -> tuple[tour.Line, ...]:
    return tuple(ln for ln in tour.TOUR if ln.command in commands)


QUICK = {"rnhql scenarios", "rnhql scenarios --example > my.toml",
         "rnhql scenarios --check my.toml",
         "RNHQL_SCENARIO_PATH=~/my-scenarios rnhql scenarios",
         "rnhql scenarios --check my.map --start 3,43 --goal 45,5",
         "rnhql report [--figures] [--refresh]"}


def test_the_tour_names_every_line_it_checks():
    assert len(_lines(QUICK)) == len(QUICK)


def test_the_tours_quick_lines_run_from_an_installed_copy(installed, monkeypatch):
    monkeypatch.setattr(tour, "TOUR", _lines(QUICK))
    rows = tour.run_tour(installed, installed=True)
    assert [r["command"] for r in rows] == [ln.command for ln in tour.TOUR]
    assert all(r["passed"] for r in rows), [r for r in rows if not r["passed"]]
    assert all(r["longest_silence_s"] <= 5.0 for r in rows), rows  # never silent
    report = next(r for r in rows if r["command"].startswith("rnhql report"))
    assert report["exit"] == 2  # one line: the artifacts live in the source tree


def test_the_copy_is_not_the_checkout(installed):
    """The tour's copy holds the packages and their data, and nothing of the checkout."""
    assert (installed / "scenarios" / "cli" / "__init__.py").is_file()
    assert (installed / "sim" / "builtin" / "maps" / "arena.map").is_file()
    assert not (installed / "docs").exists() and not (installed / "tests").exists()


@pytest.mark.slow
def test_the_whole_tour_runs_from_an_installed_copy(installed):
    rows = tour.run_tour(installed, installed=True)
    assert all(r["passed"] for r in rows if r["ran"]), [r for r in rows if not r["passed"]]

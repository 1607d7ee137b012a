"""Shared fixtures: built-in scenarios and their tabular models, built once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from sim.grid import build_model
from sim.scenario_io import resolve_scenario

REPO = Path(__file__).resolve().parent.parent
MAPS = REPO / "sim" / "builtin" / "maps"


@pytest.fixture(scope="session")
def paper50():
    return resolve_scenario("paper-50")


@pytest.fixture(scope="session")
def paper50_model(paper50):
    return build_model(paper50)

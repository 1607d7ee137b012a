"""Shared fixtures: built-in scenarios and their tabular models, built once per session."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# Sweeps above exact build V* (the stochastic model of the physics world, tens of seconds
# per map): tiny test sweeps skip it; tests/test_stochastic_model.py covers V* itself.
os.environ.setdefault("RNHQL_NO_OPTIMUM", "1")

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

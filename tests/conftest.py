"""Shared fixtures: built-in scenarios and their tabular models, built once per session."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

# Sweeps above exact build V* (the stochastic model of the physics world, tens of seconds
# per map): tiny test sweeps skip it; tests/test_stochastic_model.py covers V* itself.
os.environ.setdefault("RNHQL_NO_OPTIMUM", "1")

from hypothesis import settings

from sim.grid import build_model
from sim.scenario_io import resolve_scenario

# No per-example deadline: a property test's first example can take 400 ms on a loaded
# machine (a cold cache, another job on the cores) and 0.2 ms after; a deadline then fails
# the suite for the machine's load, not for the code. Every property test uses this profile.
settings.register_profile("rnhql", deadline=None)
settings.load_profile("rnhql")

REPO = Path(__file__).resolve().parent.parent
MAPS = REPO / "sim" / "builtin" / "maps"


@pytest.fixture(autouse=True, scope="session")
def sb3_logs_in_a_session_folder(tmp_path_factory):
    """Stable-Baselines3 makes a log folder in the system's temporary folder at every
    ``learn`` (``SB3-<date>``, empty with the default logger): the SB3 tests and examples
    put theirs under pytest's session folder instead (examples run as subprocesses read
    it from the environment), so a test run leaves nothing behind in /tmp."""
    old = os.environ.get("SB3_LOGDIR")
    os.environ["SB3_LOGDIR"] = str(tmp_path_factory.mktemp("sb3-logs"))
    yield
    if old is None:
        os.environ.pop("SB3_LOGDIR", None)
    else:
        os.environ["SB3_LOGDIR"] = old


@pytest.fixture(scope="session")
def paper50():
    return resolve_scenario("paper-50")


@pytest.fixture(scope="session")
def paper50_model(paper50):
    return build_model(paper50)


def private_cache_for(*builders):
    """A fixture ``private_cache``: the disk cache in a fresh folder (``XDG_CACHE_HOME``, the
    disk cache on), and the in-memory cache of each of ``builders`` (``lru_cache``d model
    builders) emptied before and after the test. Yields the folder."""

    @pytest.fixture
    def private_cache(tmp_path, monkeypatch):
        monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
        monkeypatch.delenv("RNHQL_NO_DISK_CACHE", raising=False)
        for b in builders:
            b.cache_clear()
        yield tmp_path
        for b in builders:
            b.cache_clear()

    return private_cache


def corridor_moves(n: int) -> np.ndarray:
    """int32[n, 4]: the moves of a 1 x n corridor 0-1-...-(n-1) (0 up, 1 down, 2 left,
    3 right; -1 off the arena), as a learner's free space holds them."""
    nb = np.full((n, 4), -1, np.int32)
    for s in range(n):
        nb[s, 2] = s - 1 if s > 0 else -1
        nb[s, 3] = s + 1 if s < n - 1 else -1
    return nb


def open_geometry_3x3():
    """A learner's geometry of a 3 x 3 open arena, G in the far corner (8)."""
    from learning.geometry import Geometry

    ix, iy = np.meshgrid(np.arange(3), np.arange(3))
    coords = (np.column_stack([ix.ravel(), iy.ravel()]) + 0.5).astype(np.float64)
    return Geometry(coords=coords, goal=8, bounds_m=(0.0, 0.0, 3.0, 3.0), n_states=9,
                    n_actions=4)

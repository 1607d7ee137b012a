"""The suite's maps are scenarios a user can name, and so are a user's own folders."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from scenarios.experiments.suite import read_map, shipped_suite_tomls
from sim.scenario_io import builtin_dir, builtin_names, resolve_scenario


def test_shipped_suite_scenarios_are_what_the_generator_writes():
    """The TOMLs and generated maps in scenarios/builtin are the suite's, byte for byte
    (regenerate with shipped_suite_tomls if a generator changes)."""
    for name, (text, free) in shipped_suite_tomls().items():
        assert (builtin_dir() / f"{name}.toml").read_text() == text, name
        if free is not None:
            assert np.array_equal(read_map(builtin_dir() / "maps" / f"{name}.map"), free), name


def test_suite_maps_resolve_by_name():
    names = builtin_names()
    for name in ("maze-1", "rooms-101", "room-32-32-8", "paper-50"):
        assert name in names
    sc = resolve_scenario("maze-1")
    assert sc.name == "maze-1" and (sc.nx, sc.ny) == (31, 31)


def test_a_folder_on_the_scenario_path_adds_names(tmp_path, monkeypatch):
    (tmp_path / "my-room.toml").write_text(
        'name = "my-room"\nstart = [1, 1]\ngoal = [8, 8]\n\n[arena]\nwidth_m = 10\n'
        "height_m = 10\ncell_size_m = 1.0\n")
    monkeypatch.setenv("RNHQL_SCENARIO_PATH", str(tmp_path))
    assert "my-room" in builtin_names()
    assert resolve_scenario("my-room").goal == (8, 8)
    out = subprocess.run([sys.executable, "-m", "scenarios.cli", "scenarios"],
                         capture_output=True, text=True, check=True).stdout
    assert "my-room" in out and "maze-1" in out

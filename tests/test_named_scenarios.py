"""The suite's maps are scenarios a user can name, and so are a user's own folders."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from scenarios.studies.maps.suite import shipped_suite_tomls
from sim.maps.movingai import read_free_grid
from sim.scenario_io import builtin_dir, builtin_names, resolve_scenario


def test_shipped_suite_scenarios_are_what_the_generator_writes():
    """The TOMLs and generated maps in sim/builtin are the suite's, byte for byte
    (regenerate with shipped_suite_tomls if a generator changes)."""
    for name, (text, free) in shipped_suite_tomls().items():
        assert (builtin_dir() / f"{name}.toml").read_text() == text, name
        if free is not None:
            shipped = read_free_grid(builtin_dir() / "maps" / f"{name}.map")
            assert np.array_equal(shipped, free), name


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


def test_the_builtin_scenarios_are_sims_package_data():
    """sim reads its built-ins from its own package, and pyproject's package-data ships every
    data file there, so a non-editable install finds them too."""
    import tomllib
    from pathlib import Path

    import sim

    root = Path(sim.__file__).resolve().parent
    assert builtin_dir() == root / "builtin" and (builtin_dir() / "paper-50.toml").is_file()
    pyproject = tomllib.loads((root.parent / "pyproject.toml").read_text())
    globs = pyproject["tool"]["setuptools"]["package-data"]["sim.builtin"]
    shipped = {p for g in globs for p in builtin_dir().glob(g)}
    data = {p for p in builtin_dir().rglob("*")
            if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts}
    assert data - shipped == set(), sorted(str(p) for p in data - shipped)

"""The continuous optimum: between the straight line and the grid route, a path the disc
can drive, and in every physics run's record."""

from __future__ import annotations

import math

import pytest

from sim.grid import build_model
from sim.physics.models.optimum import continuous_optimum_m
from sim.scenario_io import resolve_scenario


@pytest.mark.parametrize("name", ["paper-40", "zigzag-50"])
def test_continuous_optimum_lies_between_the_straight_line_and_the_grid_route(name):
    sc = resolve_scenario(name)
    got = continuous_optimum_m(sc)
    (sx, sy), (gx, gy) = sc.start, sc.goal
    straight = math.hypot(gx - sx, gy - sy) * sc.cell_size_m
    grid = build_model(sc).optimal_route_length * sc.cell_size_m
    assert straight - 1e-9 <= got < grid


def test_an_open_arena_is_the_straight_line(tmp_path):
    toml = tmp_path / "open.toml"
    toml.write_text('name = "open"\nstart = [1, 1]\ngoal = [8, 5]\n[arena]\nwidth_m = 10.0\n'
                    "height_m = 10.0\n")
    assert continuous_optimum_m(resolve_scenario(str(toml))) == pytest.approx(math.hypot(7, 4))


def test_physics_records_carry_it():
    from scenarios.runs.run import run_one
    from scenarios.runs.spec import RunSpec

    rec = run_one(RunSpec("paper-40", "haql", 0, 3, world="physics"))
    assert rec["continuous_optimal_route_m"] == pytest.approx(
        continuous_optimum_m(resolve_scenario("paper-40")), abs=1e-4)

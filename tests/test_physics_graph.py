"""The physics world's own tabular model: what physics runs are graded against."""

from __future__ import annotations

import numpy as np
import pytest

from scenarios.runs.spec import load
from sim.physics.models.transition import cache_dir, physics_model
from tests.conftest import private_cache_for


@pytest.fixture(scope="module")
def paper40():
    return load("paper-40")


private_cache = private_cache_for(physics_model)


def test_agrees_with_the_grid_on_every_free_move_and_the_optimum(paper40, private_cache):
    sc, grid = paper40
    pm = physics_model(sc)
    n = grid.n_states
    free = (grid.next_state != np.arange(n)[:, None]) & (grid.distance_to_goal[:, None] > 0)
    reached = np.zeros(n, dtype=bool)
    reached[np.unique(pm.next_state)] = True
    mask = free & reached[:, None]
    assert mask.sum() > 1000
    np.testing.assert_array_equal(pm.next_state[mask], grid.next_state[mask])
    # the real disc fits into cells only the grid's clearance blocks: the physics
    # optimum can only be as short or shorter
    assert pm.optimal_route_length <= grid.optimal_route_length
    assert ((pm.distance_to_goal >= 0) & (grid.distance_to_goal < 0)).any()


def test_cache_round_trip_and_a_corrupt_file_is_rebuilt(paper40, private_cache):
    sc, _ = paper40
    first = physics_model(sc)
    files = list(cache_dir().glob("*.npz"))
    assert len(files) == 1
    physics_model.cache_clear()
    again = physics_model(sc)  # from disk
    np.testing.assert_array_equal(first.next_state, again.next_state)
    files[0].write_bytes(b"garbage")
    physics_model.cache_clear()
    rebuilt = physics_model(sc)
    np.testing.assert_array_equal(first.next_state, rebuilt.next_state)
    assert np.load(files[0])["next_state"].shape == first.next_state.shape


def test_a_physics_run_is_graded_against_the_physics_optimum():
    from scenarios.runs.run import run_one
    from scenarios.runs.spec import RunSpec

    rec = run_one(RunSpec("paper-40", "haql", 0, 20, world="physics"))
    assert rec["physics_optimal_route_length"] == rec["optimal_route_length"]
    assert rec["grid_optimal_route_length"] == 60
    assert rec["final_route_optimal"] == (rec["final_route_length"] ==
                                          rec["physics_optimal_route_length"])

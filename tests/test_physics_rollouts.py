"""Several policies driven in one env (:func:`sim.physics.models.rollouts.drive_policies`, the
periodic tests of many runs at once) equal each policy driven alone."""

from __future__ import annotations

import numpy as np
import pytest

from sim.grid import build_model
from sim.physics.fidelity import parse_fidelity
from sim.physics.models.rollouts import drive_policies, drive_policy
from sim.scenario_io import resolve_scenario


@pytest.mark.parametrize("fidelity", ["noisy", "localised"])
def test_policies_driven_together_equal_each_driven_alone(fidelity):
    sc = resolve_scenario("paper-40")
    model = build_model(sc)
    fid = parse_fidelity(fidelity)
    # one policy that follows the grid's shortest routes, two that push into a wall
    dist = np.where(model.distance_to_goal < 0, 10**9, model.distance_to_goal)
    greedy = np.argmin(dist[model.next_state], axis=1).astype(np.int64)
    up, left = np.zeros(model.n_states, np.int64), np.full(model.n_states, 2, np.int64)
    tables = [up, greedy, left]
    seeds, tags = [3, 4, 3], [10, 20, 30]
    together = drive_policies(sc, tables, fid, 4, seeds, tags, max_steps=60, keep_routes=True)
    for table, seed, tag, got in zip(tables, seeds, tags, together, strict=True):
        alone = drive_policy(sc, table, fid, 4, seed, tag, max_steps=60, keep_routes=True)
        np.testing.assert_array_equal(got.reached, alone.reached)
        np.testing.assert_array_equal(got.primitives, alone.primitives)
        np.testing.assert_array_equal(got.contacts, alone.contacts)
        np.testing.assert_array_equal(got.bumps, alone.bumps)
        np.testing.assert_array_equal(got.sim_time_s, alone.sim_time_s)
        assert got.routes == alone.routes
    assert sum(int(r.bumps.sum()) for r in together) > 0  # contacts were exercised
    assert together[1].reached.any()  # the route-following policy gets there


def test_drive_policies_refuses_an_env_of_another_size():
    sc = resolve_scenario("paper-40")
    model = build_model(sc)
    from sim.physics.models.rollouts import rollout_env

    fid = parse_fidelity("noisy")
    env = rollout_env(sc, 3, fid)
    with pytest.raises(ValueError, match="len\\(tables\\) x n"):
        drive_policies(sc, [np.zeros(model.n_states, np.int64)] * 2, fid, 2, [0, 0], [0, 0],
                       env=env)


@pytest.mark.parametrize("n", [10, 7])
def test_a_median_only_drive_keeps_the_median_and_rollout_0(n):
    """Periodic tests read a policy's median and its rollout 0: drives that cannot change the
    median are cut (half missed already, or half and one reached G sooner), and both stay
    the whole drives' own, for policies that always, sometimes and never get there."""
    sc = resolve_scenario("paper-40")
    model = build_model(sc)
    fid = parse_fidelity("noisy")
    dist = np.where(model.distance_to_goal < 0, 10**9, model.distance_to_goal)
    greedy = np.argmin(dist[model.next_state], axis=1).astype(np.int64)
    rng = np.random.default_rng(5)
    tables = [np.where(rng.random(model.n_states) < p, rng.integers(0, 4, model.n_states),
                       greedy).astype(np.int64) for p in (0.0, 0.1, 0.25, 0.4, 1.0)]
    tables.append(np.zeros(model.n_states, np.int64))  # pushes into a wall: never
    seeds, tags = list(range(len(tables))), [7] * len(tables)
    budget = 3 * model.optimal_route_length + 20
    whole = drive_policies(sc, tables, fid, n, seeds, tags, max_steps=budget,
                           keep_routes=True)
    cut = drive_policies(sc, tables, fid, n, seeds, tags, max_steps=budget,
                         keep_routes=True, median_only=True)
    for w, c in zip(whole, cut, strict=True):
        assert c.median_primitives() == w.median_primitives()
        assert (c.reached[0], c.primitives[0], c.routes[0]) == \
            (w.reached[0], w.primitives[0], w.routes[0])
    medians = [w.median_primitives() for w in whole]
    assert np.isfinite(medians).any() and np.isinf(medians).any()  # both kinds were met
    assert sum(int(c.primitives.sum()) for c in cut) < 0.8 * sum(
        int(w.primitives.sum()) for w in whole)

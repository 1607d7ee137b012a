"""Several policies driven in one env (:func:`sim.physics.models.rollouts.drive_policies`, the
periodic tests of many runs at once) equal each policy driven alone."""

from __future__ import annotations

import numpy as np
import pytest

from sim.grid import build_model
from sim.physics.fidelity import parse_fidelity
from sim.physics.models.rollouts import drive_epsilon_greedy, drive_policies, drive_policy
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


@pytest.mark.parametrize("fidelity", ["noisy", "open-loop"])
def test_an_epsilon_greedy_drive_in_compiled_code_equals_the_env_drive(fidelity):
    """drive_epsilon_greedy draws each round's exploration ahead and drives in compiled
    code; the env drive of the same policy as a Python function draws round by round. Same
    rollouts, and the generator left in the same state (the caller draws on from it)."""
    sc = resolve_scenario("paper-40")
    model = build_model(sc)
    fid = parse_fidelity(fidelity)
    dist = np.where(model.distance_to_goal < 0, 10**9, model.distance_to_goal)
    greedy = np.argmin(dist[model.next_state], axis=1).astype(np.int64)
    for eps, seed in ((0.1, 1), (0.5, 2)):
        rng_a, rng_b = np.random.default_rng(seed), np.random.default_rng(seed)

        def policy(s, rng=rng_b, eps=eps):
            explore = rng.random(s.size) < eps
            return np.where(explore, rng.integers(0, 4, s.size), greedy[s])

        got = drive_epsilon_greedy(sc, greedy, eps, rng_a, fid, 6, 9, 11, max_steps=80)
        want = drive_policy(sc, policy, fid, 6, 9, 11, max_steps=80)
        for field in ("reached", "primitives", "contacts", "bumps", "sim_time_s"):
            np.testing.assert_array_equal(getattr(got, field), getattr(want, field), field)
        assert rng_a.bit_generator.state == rng_b.bit_generator.state
        if eps < 0.2 and fidelity == "noisy":  # drives of several lengths: the
            # generator's rounds are the longest drive's
            assert got.reached.any() and len(set(got.primitives.tolist())) > 1


def test_drives_split_over_many_compiled_calls_are_the_same_drives(monkeypatch):
    """A graded drive's compiled call returns to Python every CALL_PRIMITIVES primitives
    (so Ctrl-C is served during a long final grading); the drives do not depend on where
    the calls end."""
    import sim.physics.kernel.rollout as rollout

    sc = resolve_scenario("paper-40")
    model = build_model(sc)
    fid = parse_fidelity("noisy")
    dist = np.where(model.distance_to_goal < 0, 10**9, model.distance_to_goal)
    greedy = np.argmin(dist[model.next_state], axis=1).astype(np.int64)
    tables = [greedy, np.zeros(model.n_states, np.int64)]
    kw = dict(max_steps=60, keep_routes=True, measure_metres=True, keep_path=True)
    whole = drive_policies(sc, tables, fid, 5, [1, 2], [3, 4], **kw)
    monkeypatch.setattr(rollout, "CALL_PRIMITIVES", 7)
    split = drive_policies(sc, tables, fid, 5, [1, 2], [3, 4], **kw)
    for w, c in zip(whole, split, strict=True):
        for field in ("reached", "primitives", "contacts", "bumps", "sim_time_s", "metres",
                      "path", "poses"):
            np.testing.assert_array_equal(getattr(w, field), getattr(c, field), field)
        assert w.routes == c.routes

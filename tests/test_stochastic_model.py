"""V*, the yardstick at a fidelity: the stochastic model of the physics world, its solve,
and its agreement with driven rollouts.

Tolerance (model vs >= 200 driven rollouts of the same policy, from S, within the
episode's budget): P(G) within 0.05 and the mean primitives of the episodes that reach G
within max(1 primitive, 5 %) (:mod:`sim.physics.models.stochastic_rollouts`). Checked on
paper-40 at ``noisy`` (slow: the model drives 1.4M primitives) for the model's optimal
policy and for the exact BFS policy, which grazes an obstacle and gets pinned against it
in ~7 % of episodes. The fast tests: at ``exact`` the model is the exact physics model;
the solver on hand-made models; the cache; a small map at ``noisy`` (the machinery, with
looser bounds: one build of a 36-cell map carries more sampling error).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from scenarios.runs.spec import load
from sim.physics.fidelity import parse_fidelity
from sim.physics.models.build import (
    build_stochastic_model,
    cache_dir,
    from_samples,
    stochastic_model,
)
from sim.physics.models.solve import (
    evaluate_cell_policy,
    evaluate_policy,
    shortest_route_policy,
    solve,
)
from sim.physics.models.stochastic import (
    ARRIVED,
    FACING,
    RESTING,
    RIGHT,
    Locator,
    Sampling,
    is_resting,
)
from sim.physics.models.stochastic_rollouts import (
    P_TOL,
    drive_cell_policy,
    drive_model_policy,
    primitives_tolerance,
)
from sim.physics.models.transition import physics_model
from sim.scenario import Circle, Scenario
from tests.conftest import private_cache_for

NOISY = parse_fidelity("noisy")
EXACT = parse_fidelity("exact")
# 6 x 6 m: the straight route from S up to G passes a circle with 1 cm to spare
GRAZE = Scenario(name="graze", width_m=6.0, height_m=6.0, start=(1, 0), goal=(1, 5),
                 obstacles=(Circle(3.448, 3.05, 1.6385),), steps_per_episode=60)


private_cache = private_cache_for(stochastic_model)


def test_at_exact_the_model_is_the_exact_physics_model(private_cache):
    sc, _ = load("paper-40")
    m = stochastic_model(sc, EXACT)
    pm = physics_model(sc)
    assert set(m.state_context.tolist()) == {ARRIVED} and m.sampling.samples == 1
    assert (np.diff(m.sa_ptr) == 1).all() and np.allclose(m.prob, 1.0)  # one outcome each
    cell_of = np.append(m.state_cell, pm.goal)  # G is the model's last index
    nxt = cell_of[m.dst].reshape(-1, 4)
    np.testing.assert_array_equal(nxt, pm.next_state[m.state_cell])
    reached = np.flatnonzero(pm.distance_to_goal >= 0)
    assert set(m.state_cell.tolist()) >= set(reached.tolist()) - {pm.goal}
    opt = solve(m, sc.steps_per_episode)
    assert opt.start.expected_primitives == pm.optimal_route_length == 60
    assert opt.start.p_goal_within_budget == 1.0
    assert np.array_equal(opt.value[:-1], pm.distance_to_goal[m.state_cell].astype(float))
    bfs = evaluate_cell_policy(m, shortest_route_policy(pm), sc.steps_per_episode)
    assert (bfs.expected_primitives, bfs.p_goal_within_budget) == (60.0, 1.0)
    driven = drive_model_policy(sc, m, opt.policy, n=2)
    assert (driven.p_goal, driven.mean_primitives, driven.off_model) == (1.0, 60.0, 0)


def _hand_made(budget_sc: Scenario):
    """Three states: 0 (S), 1, 2 (a dead end); 4 drives per (state, action).

    0: a0 -> 0 (3/4) or G (1/4); a1 -> 1; a2 -> 2; a3 -> 0 (a loop for ever)
    1: every action -> G;  2: every action -> 2.
    """
    g = 3
    outcomes = {(0, 0): [0, 0, 0, g], (0, 1): [1] * 4, (0, 2): [2] * 4, (0, 3): [0] * 4}
    for a in range(4):
        outcomes[(1, a)] = [g] * 4
        outcomes[(2, a)] = [2] * 4
    src = np.array([s * 4 + a for (s, a), d in outcomes.items() for _ in d])
    dst = np.array([x for d in outcomes.values() for x in d])
    sc = budget_sc
    return from_samples(EXACT, Sampling(4, 4, 1, 1, 0), sc, np.array([0, 1, 1]),
                        np.array([ARRIVED, ARRIVED, RESTING]), np.full((3, 4), np.nan), src,
                        dst, np.ones_like(src), src.size, 0.0, 0)


def test_value_iteration_avoids_improper_and_dead_end_actions():
    sc = Scenario(name="line", width_m=3.0, height_m=1.0, start=(0, 0), goal=(2, 0))
    m = _hand_made(sc)
    assert m.start == 0 and m.goal == 3
    opt = solve(m, budget=10)
    assert opt.policy[0] == 1 and opt.value[0] == pytest.approx(2.0)
    assert opt.value[1] == pytest.approx(1.0) and np.isinf(opt.value[2])
    assert opt.sure.tolist() == [True, True, False, True]
    assert opt.start.p_goal_within_budget == 1.0 and opt.start.mean_primitives_within_budget == 2
    assert solve(m, budget=1).start.p_goal_within_budget == 0.0
    slow = evaluate_policy(m, np.array([0, 0, 0]), budget=3)  # geometric: 1 / (1/4) primitives
    assert slow.expected_primitives == pytest.approx(4.0, rel=1e-6)
    assert slow.p_goal_within_budget == pytest.approx(1 - 0.75 ** 3)
    assert slow.mean_primitives_within_budget == pytest.approx(
        sum(t * 0.25 * 0.75 ** (t - 1) for t in (1, 2, 3)) / (1 - 0.75 ** 3))
    for loop in (np.array([2, 0, 0]), np.array([3, 0, 0])):  # dead end; loop for ever
        bad = evaluate_policy(m, loop, budget=10)
        assert np.isinf(bad.expected_primitives) and bad.p_goal_within_budget == 0.0
    assert np.isnan(bad.mean_primitives_within_budget)


def test_cache_round_trip_keys_and_a_corrupt_file_is_rebuilt(private_cache):
    small = Sampling(samples=2, refined=4, particles=2, particle_samples=1, seed=3)
    first = stochastic_model(GRAZE, NOISY, small)
    files = list(cache_dir().glob("*.npz"))
    assert len(files) == 1 and cache_dir().name == "stochastic-model"
    stochastic_model.cache_clear()
    again = stochastic_model(GRAZE, NOISY, small)  # from disk
    for name in ("state_cell", "state_context", "state_pose", "sa_ptr", "dst", "prob"):
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))
    assert again.build_s == first.build_s and again.primitives == first.primitives
    files[0].write_bytes(b"garbage")
    stochastic_model.cache_clear()
    rebuilt = stochastic_model(GRAZE, NOISY, small)  # same seed: the same model
    np.testing.assert_array_equal(rebuilt.dst, first.dst)
    for other in (dataclasses.replace(small, seed=4), dataclasses.replace(small, samples=3)):
        stochastic_model(GRAZE, NOISY, other)
    stochastic_model(GRAZE, parse_fidelity("noisy,wheel_noise=0.06"), small)
    assert len(list(cache_dir().glob("*.npz"))) == 4


def test_noisy_model_of_a_small_map_and_its_rollouts():
    m = build_stochastic_model(GRAZE, NOISY)
    n = m.n_states
    sums = np.bincount(m.src_sa, m.prob, minlength=4 * n)
    np.testing.assert_allclose(sums, 1.0)
    ctx = m.state_context
    assert ARRIVED not in ctx and m.state_context[m.start] == FACING + RIGHT
    rest = is_resting(ctx)
    assert rest.any() and np.isnan(m.state_pose[~rest]).all()
    cells = np.floor(m.state_pose[rest, :2] / GRAZE.cell_size_m).astype(int)
    np.testing.assert_array_equal(cells[:, 1] * GRAZE.nx + cells[:, 0], m.state_cell[rest])
    loc = Locator(m)
    for s in np.flatnonzero(rest)[:50]:
        assert loc.state(int(m.state_cell[s]), int(ctx[s]), m.state_pose[s]) == s
    budget = GRAZE.steps_per_episode
    opt = solve(m, budget)
    assert 5.0 <= opt.start.expected_primitives < 7.0 and opt.start.p_goal_within_budget > 0.99
    pi = shortest_route_policy(physics_model(GRAZE))
    bfs = evaluate_cell_policy(m, pi, budget)
    # with the bumper (a resting robot is held, a turn in place turns) nothing traps the
    # robot beside the circle any more: the old rule's trap held it there in 6-12 % of drives
    assert bfs.p_goal_within_budget > 0.9
    driven = drive_cell_policy(GRAZE, NOISY, pi, n=400, seed=5)
    assert abs(driven.p_goal - bfs.p_goal_within_budget) < 2 * P_TOL
    assert abs(driven.mean_primitives - bfs.mean_primitives_within_budget) < 1.0
    best = drive_model_policy(GRAZE, m, opt.policy, n=400, seed=5)
    assert abs(best.p_goal - opt.start.p_goal_within_budget) < P_TOL
    assert abs(best.mean_primitives - opt.start.mean_primitives_within_budget) < 1.5


@pytest.mark.slow
def test_paper40_noisy_model_agrees_with_driven_rollouts(private_cache):
    """The stated tolerance, with 1000 rollouts per policy (about 2 minutes)."""
    sc, _ = load("paper-40")
    m = stochastic_model(sc, NOISY)
    budget = sc.steps_per_episode
    opt = solve(m, budget)
    assert opt.start.expected_primitives == pytest.approx(60.0, abs=0.5)
    pi = shortest_route_policy(physics_model(sc))
    checks = [(opt.start, drive_model_policy(sc, m, opt.policy, n=1000, seed=11)),
              (evaluate_cell_policy(m, pi, budget),
               drive_cell_policy(sc, NOISY, pi, n=1000, seed=11))]
    for model, driven in checks:
        assert abs(model.p_goal_within_budget - driven.p_goal) <= P_TOL
        assert abs(model.mean_primitives_within_budget - driven.mean_primitives) <= \
            primitives_tolerance(driven.mean_primitives)
    # (before the bumper the BFS policy got pinned against walls here, P(G)
    # below 0.97; a bump is now an event with travel and it reaches G in every drive, so
    # both checks compare a policy that always arrives; the misses a model must predict
    # are checked in test_value_iteration_avoids_improper_and_dead_end_actions)

"""Spearman's rank correlation of the methods, grid vs rung, and its bootstrap over seeds."""

from __future__ import annotations

import math

import numpy as np

from scenarios.studies.ladder.predictivity import (
    deployed_grid,
    deployed_rung,
    ranks,
    spearman,
    srcc,
)


def test_ties_share_their_mean_rank_and_spearman_matches_its_definition():
    assert ranks(np.array([3.0, 1.0, 3.0, 2.0])).tolist() == [3.5, 1.0, 3.5, 2.0]
    a, b = np.array([1.0, 2.0, 3.0, 4.0, 5.0]), np.array([2.0, 1.0, 4.0, 3.0, 5.0])
    d = ranks(a) - ranks(b)
    assert math.isclose(spearman(a, b), 1 - 6 * (d**2).sum() / (5 * (25 - 1)))  # the formula
    assert spearman(a, -a) == -1.0
    assert math.isnan(spearman(np.ones(4), a[:4]))  # no spread: undefined


def _run(method, world, seed, length=None, p_goal=1.0, prims=10.0, steps=(50, 40)):
    r = {"method": method, "world": world, "seed": seed, "steps_per_episode": list(steps)}
    if world == "grid":
        r["final_route_length"] = length
    else:
        r["final_policy"] = {"p_goal": p_goal, "primitives_mean": prims if p_goal else None}
    return r


def test_a_miss_costs_the_budget_in_both_worlds():
    assert deployed_grid(_run("a", "grid", 0, length=-1), 600) == 600
    assert deployed_grid(_run("a", "grid", 0, length=80), 600) == 80
    assert deployed_rung(_run("a", "physics", 0, p_goal=0.0), 600) == 600
    assert deployed_rung(_run("a", "physics", 0, p_goal=0.5, prims=80.0), 600) == 340


def test_the_same_order_in_both_worlds_is_rho_one_and_a_reversed_one_minus_one():
    runs, rev = [], []
    for k, m in enumerate(("a", "b", "c", "d")):
        for s in range(5):
            runs.append(_run(m, "grid", s, length=60 + 10 * k + s % 2, steps=(100 + k,)))
            runs.append(_run(m, "physics", s, prims=60.0 + 10 * k + s % 2, steps=(90 + k,)))
            rev.append(_run(m, "grid", s, length=60 + 10 * k, steps=(100 + k,)))
            rev.append(_run(m, "physics", s, prims=90.0 - 10 * k, steps=(100 - k,)))
    same = srcc(runs, 600, n_boot=200)
    assert same["deployed"]["rho"] == 1.0 and same["learning"]["rho"] == 1.0
    assert same["deployed"]["ci95"] == [1.0, 1.0]  # every resample keeps the order
    other = srcc(rev, 600, n_boot=200)
    assert other["deployed"]["rho"] == -1.0 and other["learning"]["rho"] == -1.0
    assert other["deployed"]["methods"] == ["a", "b", "c", "d"]


def test_noisy_seeds_widen_the_interval_and_a_world_without_spread_is_undefined():
    rng = np.random.default_rng(0)
    runs = []
    for k, m in enumerate(("a", "b", "c", "d")):
        for s in range(10):
            runs.append(_run(m, "grid", s, length=-1, steps=(100 + k,)))  # nobody reaches G
            runs.append(_run(m, "physics", s, prims=60.0 + 3 * k + rng.normal(0, 6),
                             steps=(100 + k + rng.normal(0, 4),)))
    res = srcc(runs, 600, n_boot=300)
    assert res["deployed"]["rho"] is None and res["deployed"]["ci95"] is None
    lo, hi = res["learning"]["ci95"]
    assert -1.0 <= lo < hi <= 1.0 and hi - lo > 0.2

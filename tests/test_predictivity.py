"""Spearman's rank correlation of the methods, grid vs rung, and its bootstrap over seeds."""

from __future__ import annotations

import math

import numpy as np

from scenarios.studies.ladder.predictivity import (
    control_variate,
    cv_variance_factor,
    deployed_grid,
    deployed_rung,
    mmrv,
    r_interval,
    ranks,
    seed_spread,
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


def test_mmrv_weighs_a_swap_by_how_far_apart_the_rung_puts_the_two():
    """SIMPLER's definition, worked by hand: the grid orders a < b < c; the rung swaps b and c
    (near-tied: 1 apart) in one case, a and c (10 apart) in the other. Spearman is the same
    for both swaps of neighbours, MMRV is not."""
    grid = np.array([1.0, 2.0, 3.0])
    assert mmrv(grid, np.array([10.0, 20.0, 30.0])) == 0.0  # the same order
    # b, c swapped at the rung (20 vs 19): b and c each violated by 1, a by nothing
    assert math.isclose(mmrv(grid, np.array([10.0, 20.0, 19.0])), (0 + 1 + 1) / 3)
    # a, b swapped far apart (10 vs 0): a and b each violated by 10
    assert math.isclose(mmrv(grid, np.array([10.0, 0.0, 30.0])), (10 + 10 + 0) / 3)
    assert spearman(grid, np.array([10.0, 20.0, 19.0])) == spearman(
        grid, np.array([10.0, 0.0, 30.0]))


def test_the_control_variate_removes_the_variance_the_grid_explains():
    rng = np.random.default_rng(1)
    x = rng.normal(size=10)
    same = control_variate(x, 3.0 * x + 1.0)  # the rung a function of the grid: all of it
    assert same["r"] == 1.0 and same["variance_reduction"] == 1.0 and same["saving_shown"]
    assert same["seeds_with_grid"] == 4  # the estimated beta needs m > 3 seeds
    flat = control_variate(np.ones(10), x)  # a grid without spread explains nothing
    assert flat["r"] == 0.0 and not flat["saving_shown"] and flat["seeds_with_grid"] == 10
    # the claim itself: over many draws, Y - beta (X - mu_X) has (1 - r^2) of Y's variance
    n, r = 200_000, 0.8
    x = rng.normal(size=n)
    y = r * x + math.sqrt(1 - r * r) * rng.normal(size=n)
    beta = np.cov(x, y)[0, 1] / x.var()
    assert math.isclose((y - beta * x).var() / y.var(), 1 - r * r, rel_tol=0.02)


def test_the_control_variate_by_hand():
    """r = 0.6 from 10 seeds: Fisher's z interval tanh(0.693 -+ 1.96 / sqrt 7 = 0.741) =
    [-0.05, 0.89] covers 0, so no saving is claimed; r = 0.9: tanh(1.472 -+ 0.741) =
    [0.62, 0.98], and the fewest m with (1 - 0.81)(m - 2) / ((m - 3) m) <= 1/10 is 4."""
    lo, hi = r_interval(0.6, 10)
    assert (round(lo, 2), round(hi, 2)) == (-0.05, 0.89)
    lo, hi = r_interval(0.9, 10)
    assert (round(lo, 2), round(hi, 2)) == (0.62, 0.98)
    # m = 4: 0.19 * 2 / (1 * 4) = 0.095 <= 0.1: four seeds give the interval of ten
    assert math.isclose(cv_variance_factor(0.9, 4), 0.38)
    assert cv_variance_factor(0.9, 3) == math.inf
    x = np.arange(10.0)
    noise = np.array([1, -1, 1, -1, 1, -1, 1, -1, 1, -1], float)
    for k, want_shown in ((0.3, True), (30.0, False)):
        cv = control_variate(x, x + k * noise)
        assert cv["saving_shown"] == want_shown
        if not want_shown:
            assert cv["seeds_with_grid"] == 10
    # at rho = 0 the estimated beta makes things worse, never better: (n - 2) / (n - 3) > 1
    assert cv_variance_factor(0.0, 10) == 8 / 7


def test_the_interval_of_r_covers_rho_as_often_as_it_says():
    """Coverage at the study's n = 10, by simulation: about 95 %."""
    rng = np.random.default_rng(3)
    rho, n, hits, trials = 0.5, 10, 0, 2000
    for _ in range(trials):
        x = rng.normal(size=n)
        y = rho * x + math.sqrt(1 - rho * rho) * rng.normal(size=n)
        lo, hi = r_interval(float(np.corrcoef(x, y)[0, 1]), n)
        hits += lo <= rho <= hi
    assert 0.93 <= hits / trials <= 0.97


def test_a_rung_is_predictive_only_with_a_high_rho_and_violations_within_the_seed_spread():
    runs = []
    for k, m in enumerate("abcdef"):
        for s in range(6):
            runs.append(_run(m, "grid", s, length=60 + 20 * k, steps=(100 + k,)))
            # the rung: the same order but e and f swapped, 1 primitive apart, well within
            # the seeds' spread of 4
            prims = 60.0 + 20 * min(k, 4) + (s % 3) * 2 - (1.0 if k == 5 else 0.0)
            runs.append(_run(m, "physics", s, prims=prims, steps=(100 + k,)))
    p = srcc(runs, 600, n_boot=100)["deployed"]
    assert p["rho"] >= 0.85 and 0.0 < p["mmrv"] <= p["seed_spread"]
    assert p["predictive"]
    assert seed_spread([np.array([0.0, 1.0, 2.0, 3.0, 4.0])]) == 2.0
    far = [r if r["world"] == "grid" or r["method"] != "f" else
           _run("f", "physics", r["seed"], prims=20.0) for r in runs]  # f now the best
    q = srcc(far, 600, n_boot=100)["deployed"]
    assert q["mmrv"] > q["seed_spread"] and not q["predictive"]
    assert set(q["control_variate"]) == set("abcdef")

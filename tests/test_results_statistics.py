"""Bootstrap intervals and the probability of improvement, and what the verdict makes of them."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from scenarios.runs.results import summarise, summary_markdown, verdict
from scenarios.runs.statistics import (
    bootstrap_ci,
    generator,
    percentile_interval,
    probability_of_improvement,
)


def test_x_all_better_than_y_is_certain_improvement():
    est = probability_of_improvement([1, 2, 3], [4, 5, 6], generator(), lower_is_better=True)
    assert (est.value, est.lo, est.hi) == (1.0, 1.0, 1.0)
    est = probability_of_improvement([1, 2, 3], [4, 5, 6], generator())  # higher is better
    assert (est.value, est.lo, est.hi) == (0.0, 0.0, 0.0)


def test_identical_samples_are_no_evidence():
    x = [10, 20, 30, 40, 50]
    est = probability_of_improvement(x, x, generator())
    assert est.value == 0.5
    assert est.lo < 0.5 < est.hi and est.contains(0.5)
    tied = probability_of_improvement([7, 7, 7], [7, 7, 7], generator())
    assert (tied.value, tied.lo, tied.hi) == (0.5, 0.5, 0.5)  # every pair is a tie: ½


def test_point_value_counts_ties_as_half():
    # pairs: (1,1) tie, (1,2) win, (3,1) loss, (3,2) loss -> (0.5 + 1) / 4 lower-is-better
    est = probability_of_improvement([1, 3], [1, 2], generator(), lower_is_better=True)
    assert est.value == pytest.approx(0.375)
    assert 0.0 <= est.lo <= est.value <= est.hi <= 1.0


def test_same_seed_same_interval_other_seed_other_resamples():
    rng_values = np.random.default_rng(0).normal(size=12).tolist()
    other = (np.random.default_rng(1).normal(size=9) + 0.3).tolist()
    a = probability_of_improvement(rng_values, other, generator(5))
    b = probability_of_improvement(rng_values, other, generator(5))
    assert a == b
    assert bootstrap_ci(rng_values, rng=generator(5)) == bootstrap_ci(rng_values,
                                                                      rng=generator(5))
    # (a median's percentiles land on a few order statistics; a mean's show the resamples)
    def mean(a):
        return a.mean(axis=-1)

    assert bootstrap_ci(rng_values, mean, generator(5)) == bootstrap_ci(rng_values, mean,
                                                                        generator(5))
    assert bootstrap_ci(rng_values, mean, generator(5)) != bootstrap_ci(rng_values, mean,
                                                                        generator(6))


def test_bootstrap_ci_of_the_median_brackets_it_and_narrows_with_seeds():
    rng = np.random.default_rng(3)
    few, many = rng.normal(100, 10, size=8), rng.normal(100, 10, size=400)
    lo_f, hi_f = bootstrap_ci(few.tolist(), rng=generator())
    lo_m, hi_m = bootstrap_ci(many.tolist(), rng=generator())
    assert lo_f <= np.median(few) <= hi_f and lo_m <= np.median(many) <= hi_m
    assert hi_m - lo_m < (hi_f - lo_f) / 2
    assert 95 < lo_m < 100 < hi_m < 105
    assert bootstrap_ci([42], rng=generator()) == (42.0, 42.0)
    # a vectorised statistic of the caller's choosing: the mean of 0/1 outcomes
    lo, hi = bootstrap_ci([0, 1] * 50, lambda a: a.mean(axis=-1), generator())
    assert 0.38 < lo < 0.5 < hi < 0.62


def test_never_counts_as_infinity():
    # one never in ten: a resample's median is only infinite when it drew >= 5 of them
    lo, hi = bootstrap_ci([10, 11, 12, 13, 14, 15, 16, 17, 18, None], rng=generator())
    assert 10 <= lo and math.isfinite(hi)
    # half never: the interval's top end is never, the bottom still finite
    lo, hi = bootstrap_ci([10, 20, 30, None, None, None], rng=generator())
    assert math.isfinite(lo) and hi == math.inf
    assert bootstrap_ci([None, None], rng=generator()) == (math.inf, math.inf)
    # percentiles interpolating towards infinity give infinity, never NaN
    assert percentile_interval(np.array([1.0, math.inf]), 0.5) == (math.inf, math.inf)
    # None loses to every value and ties with None, whichever way the figure runs
    est = probability_of_improvement([5, None], [None, None], generator(), lower_is_better=True)
    assert est.value == pytest.approx((1 + 1 + 0.5 + 0.5) / 4)
    est = probability_of_improvement([0.1], [None], generator())  # higher is better
    assert est.value == 1.0


def run(method: str, seed: int, stable: int | None, world: str = "grid",
        success: float = 0.8) -> dict:
    ok = stable is not None
    return {"method": method, "seed": seed, "world": world,
            "episodes_to_stable_optimal": stable, "episodes_to_optimal": stable,
            "final_route_length": 60 if ok else -1, "final_route_optimal": ok,
            "success_rate": success, "wall_time_s": 1.0 + seed}


def results_of(runs: list[dict]) -> dict:
    return {"summary": summarise(runs), "runs": runs, "episodes": 300, "world": "grid",
            "scenario": {"name": "synthetic", "rewards": None}, "optimal_route_length": 60}


def test_summary_carries_the_medians_ci_and_keeps_the_old_keys():
    runs = [run("rnh-ql", s, 20 + s) for s in range(6)] + \
           [run("haql", s, None if s < 4 else 30) for s in range(6)]
    summ = summarise(runs)
    stable = summ["rnh-ql"]["grid"]["episodes_to_stable_optimal"]
    assert set(stable) == {"median", "q25", "q75", "ci95"}
    assert stable["median"] == 22.5 and stable["q25"] == 21.25 and stable["q75"] == 23.75
    lo, hi = stable["ci95"]
    assert 20 <= lo <= 22.5 <= hi <= 25
    assert summ["haql"]["grid"]["episodes_to_stable_optimal"]["ci95"][1] is None  # never
    json.dumps(summ, allow_nan=False)  # no inf/NaN leaks into results.json
    assert summarise(runs) == summ  # deterministic
    md = summary_markdown(results_of(runs))
    assert "| rnh-ql | grid | 6 | 100% | 22 [21, 24] | [" in md
    assert "95 % CI" in md and "probability of improvement" in md


def test_verdict_names_the_winner_when_the_seeds_separate():
    runs = [run("rnh-ql", s, 20 + s) for s in range(10)] + \
           [run("st-ql", s, 200 + s) for s in range(10)]
    lines = verdict(results_of(runs))
    assert lines[0].startswith("- grid: RNH-QL ranks first")
    assert "RNH-QL is better than st-ql" in lines[0]
    assert ("RNH-QL vs st-ql: P(RNH-QL better) = 1.00, 95 % CI [1.00, 1.00] on episodes to "
            "a stable optimal route (never = last), 10 × 10 seeds: RNH-QL is better.") in lines[1]
    assert "no evidence" not in "\n".join(lines)
    # the other way round: a loss backed by the seeds says who is better
    runs = [run("rnh-ql", s, 200 + s) for s in range(10)] + \
           [run("haql", s, 20 + s) for s in range(10)]
    lines = verdict(results_of(runs))
    assert "RNH-QL does NOT win" in lines[0] and "haql is better" in lines[0]
    assert lines[1].endswith("haql is better.")


def test_verdict_says_no_evidence_when_the_seeds_overlap():
    runs = [run("rnh-ql", s, 20 + 10 * s) for s in range(6)] + \
           [run("st-ql", s, 25 + 10 * s) for s in range(6)]
    lines = verdict(results_of(runs))
    assert lines[0].startswith("- grid: RNH-QL ranks first")  # on medians, yes
    assert "no evidence of a difference from st-ql" in lines[0]  # but not on the seeds
    assert lines[1].endswith("no evidence of a difference.")
    assert "is better" not in "\n".join(lines)


def test_verdict_speaks_for_rnh_ql_plus_and_uses_success_rate_when_nothing_is_optimal():
    runs = [run("rnh-ql+", s, 20 + s) for s in range(8)] + \
           [run("rnh-ql", s, 40 + s) for s in range(8)] + \
           [run("dyna-q", s, 21 + s) for s in range(8)]
    text = "\n".join(verdict(results_of(runs)))
    assert "RNH-QL vs rnh-ql+: P(RNH-QL better) = 0.00" in text  # each pair once
    assert "rnh-ql+ is better." in text and "rnh-ql+ vs rnh-ql" not in text
    assert "rnh-ql+ vs dyna-q: P(rnh-ql+ better) = " in text and "RNH-QL vs dyna-q:" in text
    assert "dyna-q is better" in text and "no evidence of a difference" in text
    flat = [run("rnh-ql", s, None, success=0.9) for s in range(8)] + \
           [run("st-ql", s, None, success=0.1) for s in range(8)]
    text = "\n".join(verdict(results_of(flat)))
    assert "no method's final greedy route from S is optimal" in text
    assert "on training success rate" in text and "RNH-QL is better than st-ql" in text


def test_verdict_without_seeds_keeps_the_rank_alone():
    runs = [run("rnh-ql", s, 20 + s) for s in range(4)] + \
           [run("st-ql", s, 30 + s) for s in range(4)]
    res = results_of(runs)
    del res["runs"]
    assert verdict(res) == ["- grid: RNH-QL ranks first (most seeds optimal, then fewest "
                            "episodes to a stable optimal route, then most seeds reaching G, "
                            "then highest training success rate)."]


# ---------------------------------------------------------------- known values, by hand
def test_iqm_by_hand_and_against_the_trimmed_mean():
    from scenarios.runs.statistics import iqm

    assert iqm(np.array([1.0, 2.0, 3.0, 100.0])) == 2.5  # the middle half: 2 and 3
    assert iqm(np.arange(1.0, 9.0)) == 4.5  # 3, 4, 5, 6
    # n = 7: the quarter points fall at 1.75 and 5.25 runs: 2 and 32 count a quarter each,
    # (0.25 * 2 + 4 + 8 + 16 + 0.25 * 32) / 3.5 = 36.5 / 3.5; scipy's trim_mean(x, 0.25)
    # drops one whole run at each end: (2 + 4 + 8 + 16 + 32) / 5 = 12.4
    x = np.array([1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0])
    assert math.isclose(float(iqm(x)), 36.5 / 3.5)
    assert math.isclose(float(np.mean(np.sort(x)[1:-1])), 12.4)
    # a multiple of 4: the two conventions agree (trim_mean drops n / 4 at each end)
    y = np.array([5.0, 1.0, 9.0, 2.0, 7.0, 3.0, 8.0, 4.0])
    assert math.isclose(float(iqm(y)), float(np.mean(np.sort(y)[2:-2])))
    assert iqm(np.array([[1.0, 2.0, 3.0, 100.0], [4.0, 4.0, 4.0, 4.0]])).tolist() == [2.5, 4.0]


def test_stratified_iqm_by_hand():
    from scenarios.runs.statistics import stratified_iqm

    est = stratified_iqm([[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]], generator())
    assert est.value == 4.5 and est.lo <= 4.5 <= est.hi  # the IQM of all eight runs
    same = stratified_iqm([[3.0, 3.0], [3.0, 3.0, 3.0]], generator())
    assert tuple(same) == (3.0, 3.0, 3.0)  # no spread: a zero-width interval
    # the bootstrap redraws within each task: a task keeps its own values
    lo_task = stratified_iqm([[0.0] * 4, [10.0] * 4], generator())
    assert lo_task.value == 5.0 and lo_task.lo == lo_task.hi == 5.0


def test_probability_of_improvement_by_hand():
    from scenarios.runs.statistics import probability_of_improvement_tasks

    # higher is better: x = (3, 4) against y = (1, 3): 3>1, 3=3 (1/2), 4>1, 4>3 -> 3.5 / 4
    assert probability_of_improvement([3, 4], [1, 3], generator()).value == 0.875
    # a None is the worst value and ties another None
    assert probability_of_improvement([None, 2], [1, None], generator()).value == \
        (0 + 0.5 + 1 + 1) / 4
    # over tasks: the mean of the tasks' values, 0.875 and 0 (lower is better here)
    est = probability_of_improvement_tasks([[3, 4], [9, 9]], [[5, 6], [1, 2]], generator())
    assert est.value == (1.0 + 0.0) / 2 and est.lo <= est.value <= est.hi


def test_each_interval_covers_as_often_as_it_says_at_the_studys_n():
    """Coverage at 10 seeds, by simulation: the median's percentile bootstrap interval
    around a known median, 300 draws (a percentile interval at n = 10 undercovers a
    little; the bounds say how much is tolerated)."""
    rng = np.random.default_rng(5)
    hits = 0
    for _ in range(300):
        x = rng.normal(50.0, 10.0, size=10)
        lo, hi = bootstrap_ci(list(x), rng=rng, n_resamples=1000)
        hits += lo <= 50.0 <= hi
    assert 0.88 <= hits / 300 <= 0.99

"""How well the grid predicts a rung: rank correlation, rank violations, and the grid as a
control variate for the rung's seeds.

Kadian et al. (2020, "Sim2Real predictivity") rank agents by their performance in
simulation and on the real robot and report Spearman's rank correlation between the two
orders: 1 means the cheap world orders methods as the real one does. Here the cheap world
is the grid and the "real" one a rung of the fidelity ladder. Each method is ranked by
the median over seeds of a run's own figure, in the grid-trained runs (the grid's own
figures) and in the runs trained and driven at the rung:

- ``deployed``: the expected primitives of the final greedy policy from S, a drive that
  misses G costing the episode's budget (grid: the greedy route, or the budget; rung:
  ``P(G) * mean primitives + (1 - P(G)) * budget`` over its drives);
- ``learning``: the mean episode length over training (how fast the method gets good).

- ``p_goal``: the final greedy policy's chance of reaching G (grid: 1 or 0; rung: over
  its drives). Higher is better.

Spearman's rho counts every swap the same, a swap of two near-tied methods as much as one
of the best and the worst; SIMPLER (Li et al. 2024) pairs it with the mean maximum rank
violation (:func:`mmrv`), in the figure's own units: how much worse, at the rung, a method
the grid ranked above another can be. A rung is *predictive* of a figure when rho >= 0.85
(the bar of Kadian et al. 2020 and later sim-to-real studies) and its MMRV is within one
seed spread (the median over methods of the rung's interquartile range of seeds).

Both intervals are percentile bootstraps over seeds: each (method, world)'s seeds are
resampled with replacement and the medians re-ranked. Where a world cannot tell the
methods apart (every median equal) Spearman is undefined ("—").

**The grid as a control variate** (:func:`control_variate`; after Sim2Val and SureSim,
2025): a seed's grid run and its rung run share the seed's streams, so where their
figures are correlated, the rung mean corrected by the grid's (``Y - beta (X - mu_X)``,
``mu_X`` pinned by many cheap grid seeds) has variance ``(1 - r^2)`` times the plain
mean's. The same interval then needs ``n (1 - r^2)`` rung seeds instead of ``n``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

FIGURES = ("deployed", "learning", "p_goal")
BOOTSTRAP = 2000
PREDICTIVE_RHO = 0.85  # Kadian et al. 2020 (0.875), EmbodiedSplat (0.87-0.97)


def deployed_grid(run: dict[str, Any], budget: int) -> float:
    """The grid run's final greedy route from S [moves] (the budget if it misses G)."""
    length = run.get("final_route_length")
    return float(length) if length is not None and length > 0 else float(budget)


def deployed_rung(run: dict[str, Any], budget: int) -> float:
    """Expected primitives of the final policy's drives at the rung, a miss costing the
    budget."""
    fp = run["final_policy"]
    p = float(fp["p_goal"])
    prims = fp.get("primitives_mean")
    return p * float(prims) + (1.0 - p) * budget if prims is not None else float(budget)


def p_goal(run: dict[str, Any]) -> float:
    """The final greedy policy's P(G): the grid route reaches G or not; a rung's drives."""
    if run["world"] == "grid":
        length = run.get("final_route_length")
        return 1.0 if length is not None and length > 0 else 0.0
    return float(run["final_policy"]["p_goal"])


def learning(run: dict[str, Any]) -> float:
    """Mean episode length over training [steps]."""
    return float(np.mean(run["steps_per_episode"]))


def ranks(values: np.ndarray) -> np.ndarray:
    """Ranks 1..n, ties sharing their mean rank."""
    order = np.argsort(values, kind="stable")
    r = np.empty(len(values))
    r[order] = np.arange(1, len(values) + 1)
    for v in np.unique(values):
        tie = values == v
        if tie.sum() > 1:
            r[tie] = r[tie].mean()
    return r


def spearman(a: np.ndarray, b: np.ndarray) -> float:
    """Spearman's rho of two orders (nan when either has no spread)."""
    ra, rb = ranks(np.asarray(a, float)), ranks(np.asarray(b, float))
    if ra.std() == 0.0 or rb.std() == 0.0:
        return float("nan")
    return float(np.clip(round(float(np.corrcoef(ra, rb)[0, 1]), 12), -1.0, 1.0))


def mmrv(grid: np.ndarray, rung: np.ndarray) -> float:
    """SIMPLER's mean maximum rank violation of the rung's figures ``rung`` by the grid's
    order ``grid``: for each method, the largest ``|rung_i - rung_j|`` over the methods j
    the two worlds order differently against it; the mean over methods. 0 when the orders
    agree; in the figure's units."""
    g, r = np.asarray(grid, float), np.asarray(rung, float)
    violated = (g[:, None] < g[None, :]) != (r[:, None] < r[None, :])
    gap = np.abs(r[:, None] - r[None, :])
    return float(np.where(violated, gap, 0.0).max(axis=1).mean()) if len(g) else 0.0


def seed_spread(per_method: list[np.ndarray]) -> float:
    """The median over methods of the interquartile range of their seeds."""
    iqr = [float(np.subtract(*np.quantile(v, [0.75, 0.25]))) for v in per_method]
    return float(np.median(iqr)) if iqr else 0.0


def r_interval(r: float, n: int, z95: float = 1.959964) -> tuple[float, float]:
    """The 95 % interval of a correlation from ``n`` pairs (Fisher's z: atanh r is about
    normal with standard error 1 / sqrt(n - 3)); the whole range below 4 pairs."""
    if n < 4:
        return -1.0, 1.0
    z = math.atanh(min(max(r, -0.999999), 0.999999))
    half = z95 / math.sqrt(n - 3)
    return math.tanh(z - half), math.tanh(z + half)


def cv_variance_factor(r: float, m: int) -> float:
    """The control-variate mean's variance over the plain mean's, from ``m`` paired seeds
    with the coefficient beta estimated from the same seeds: (1 - r^2) (m - 2) / (m - 3)
    (the estimated beta costs a degree of freedom; at small m it eats the saving)."""
    return (1.0 - r * r) * (m - 2) / (m - 3) if m > 3 else math.inf


def control_variate(grid: np.ndarray, rung: np.ndarray) -> dict[str, Any]:
    """One method's seeds, paired (seed k's grid run and rung run): the correlation r with
    its 95 % interval (:func:`r_interval`), the variance reduction r^2, and the rung seeds
    that would give the interval of the study's ``n`` plain seeds with the grid as a
    control variate: the fewest m with ``cv_variance_factor(r, m) / m <= 1 / n``. Where
    r's interval covers 0 the correlation is not shown to exist, and the saving is none
    (m = n); so too without spread in either world (r = 0). The saving is hypothetical:
    it takes the grid's own mean as pinned (by many cheap grid seeds, which the study
    does not run)."""
    x, y = np.asarray(grid, float), np.asarray(rung, float)
    n = len(y)
    r = 0.0
    if n >= 3 and x.std() > 0.0 and y.std() > 0.0:
        r = float(np.corrcoef(x, y)[0, 1])
    lo, hi = r_interval(r, n)
    shown = lo > 0.0 or hi < 0.0
    need = n
    if shown:
        need = next((m for m in range(4, n + 1) if cv_variance_factor(r, m) / m <= 1.0 / n), n)
    return {"r": round(r, 4), "r_ci95": [round(lo, 4), round(hi, 4)],
            "variance_reduction": round(r * r, 4), "seeds": n,
            "saving_shown": shown, "seeds_with_grid": need}


def paired_pick(rng: np.random.Generator, n_grid: int, n_rung: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """One bootstrap resample of a method's seeds: the same seeds in both worlds where both
    have every seed (paired), else each world's own draw."""
    if n_grid == n_rung:
        i = rng.integers(0, n_grid, n_grid)
        return i, i
    return rng.integers(0, n_grid, n_grid), rng.integers(0, n_rung, n_rung)


def figures_by_method(runs: list[dict[str, Any]], budget: int
                      ) -> dict[str, dict[str, dict[str, list[float]]]]:
    """figure -> world ("grid" / "rung") -> method -> per-seed values, in seed order."""
    out: dict[str, dict[str, dict[str, list[float]]]] = {
        f: {"grid": {}, "rung": {}} for f in FIGURES}
    for r in sorted(runs, key=lambda r: (r["method"], r["seed"])):
        world = "grid" if r["world"] == "grid" else "rung"
        dep = deployed_grid(r, budget) if world == "grid" else deployed_rung(r, budget)
        out["deployed"][world].setdefault(r["method"], []).append(dep)
        out["learning"][world].setdefault(r["method"], []).append(learning(r))
        out["p_goal"][world].setdefault(r["method"], []).append(p_goal(r))
    return out


def _interval(values: list[float]) -> list[float] | None:
    b = np.asarray(values, float)
    ok = b[np.isfinite(b)]
    if not ok.size:
        return None
    return [round(float(np.quantile(ok, 0.025)), 4), round(float(np.quantile(ok, 0.975)), 4)]


def srcc(runs: list[dict[str, Any]], budget: int, seed: int = 0,
         n_boot: int = BOOTSTRAP) -> dict[str, dict[str, Any]]:
    """Per figure: rho of the methods' medians (grid vs rung) and MMRV, each with its 95 %
    bootstrap interval over seeds, the share of resamples where rho was defined, the seed
    spread and whether the rung is predictive of it, each world's medians, and each
    method's control variate (the seeds paired, as the study runs them: one seed list
    for both worlds)."""
    rng = np.random.default_rng(seed)
    result = {}
    for fig, worlds in figures_by_method(runs, budget).items():
        methods = sorted(set(worlds["grid"]) & set(worlds["rung"]))
        grid = [np.asarray(worlds["grid"][m]) for m in methods]
        rung = [np.asarray(worlds["rung"][m]) for m in methods]
        med_g = np.array([np.median(v) for v in grid])
        med_r = np.array([np.median(v) for v in rung])
        enough = len(methods) >= 3
        rho = spearman(med_g, med_r) if enough else float("nan")
        violation = mmrv(med_g, med_r)
        boots, boot_mmrv = [], []
        for _ in range(n_boot if enough else 0):
            # paired: a method's grid run and rung run of a seed share its streams, so a
            # resample draws seeds, each bringing both of its runs
            picks = [paired_pick(rng, len(g), len(r)) for g, r in zip(grid, rung, strict=True)]
            bg = np.array([np.median(v[i]) for v, (i, _) in zip(grid, picks, strict=True)])
            br = np.array([np.median(v[j]) for v, (_, j) in zip(rung, picks, strict=True)])
            boots.append(spearman(bg, br))
            boot_mmrv.append(mmrv(bg, br))
        b = np.asarray(boots)
        spread = seed_spread(rung)
        result[fig] = {
            "rho": None if not np.isfinite(rho) else round(rho, 4),
            "ci95": _interval(boots),
            "defined_share": round(int(np.isfinite(b).sum()) / b.size, 4) if b.size else 0.0,
            "mmrv": round(violation, 4),
            "mmrv_ci95": _interval(boot_mmrv),
            "seed_spread": round(spread, 4),
            "predictive": bool(np.isfinite(rho) and rho >= PREDICTIVE_RHO
                               and violation <= spread),
            # the same mark on the intervals: rho's lower end and MMRV's upper end
            "predictive_interval": bool(
                np.isfinite(rho) and _interval(boots) is not None and _interval(boot_mmrv)
                is not None and _interval(boots)[0] >= PREDICTIVE_RHO
                and _interval(boot_mmrv)[1] <= spread),
            "methods": methods,
            "grid_median": [round(float(x), 3) for x in med_g],
            "rung_median": [round(float(x), 3) for x in med_r],
            "control_variate": {m: control_variate(g, r) for m, g, r
                                in zip(methods, grid, rung, strict=True) if len(g) == len(r)},
        }
    return result

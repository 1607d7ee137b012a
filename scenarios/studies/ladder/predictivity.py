"""How well the grid predicts a rung: the rank correlation of methods, grid vs rung (SRCC).

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

Lower is better for both. The interval is a percentile bootstrap over seeds: each
(method, world)'s seeds are resampled with replacement, the medians re-ranked. Where a
world cannot tell the methods apart (every median equal) Spearman is undefined ("—").
"""

from __future__ import annotations

from typing import Any

import numpy as np

FIGURES = ("deployed", "learning")
BOOTSTRAP = 2000


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
    return out


def srcc(runs: list[dict[str, Any]], budget: int, seed: int = 0,
         n_boot: int = BOOTSTRAP) -> dict[str, dict[str, Any]]:
    """Per figure: rho of the methods' medians (grid vs rung), its 95 % bootstrap interval
    over seeds, the share of resamples where rho was defined, and each world's medians."""
    rng = np.random.default_rng(seed)
    result = {}
    for fig, worlds in figures_by_method(runs, budget).items():
        methods = sorted(set(worlds["grid"]) & set(worlds["rung"]))
        grid = [np.asarray(worlds["grid"][m]) for m in methods]
        rung = [np.asarray(worlds["rung"][m]) for m in methods]
        med_g = np.array([np.median(v) for v in grid])
        med_r = np.array([np.median(v) for v in rung])
        rho = spearman(med_g, med_r) if len(methods) >= 3 else float("nan")
        boots = []
        for _ in range(n_boot if len(methods) >= 3 else 0):
            bg = [np.median(v[rng.integers(0, len(v), len(v))]) for v in grid]
            br = [np.median(v[rng.integers(0, len(v), len(v))]) for v in rung]
            boots.append(spearman(np.array(bg), np.array(br)))
        b = np.asarray(boots)
        ok = b[np.isfinite(b)]
        result[fig] = {
            "rho": None if not np.isfinite(rho) else round(rho, 4),
            "ci95": ([round(float(np.quantile(ok, 0.025)), 4),
                      round(float(np.quantile(ok, 0.975)), 4)] if ok.size else None),
            "defined_share": round(ok.size / b.size, 4) if b.size else 0.0,
            "methods": methods,
            "grid_median": [round(float(x), 3) for x in med_g],
            "rung_median": [round(float(x), 3) for x in med_r],
        }
    return result

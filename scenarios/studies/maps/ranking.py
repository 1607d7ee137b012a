"""Rankings a reviewer accepts, over a held-out study's maps (Agarwal et al. 2021).

A run's score is its **share of the episode budget** spent before its greedy route from S
became optimal for good: episodes to a stable optimal route over the run's episodes, 1.0
for a run that never got there (the whole budget spent, and nothing to show). Shares make
maps of different sizes and budgets comparable; counting "never" as the full budget is
the kindest value a failed run can get (it is not better than any run that succeeded), so
an IQM that includes failures flatters the method that failed, never the other.

Per protocol (uniform starts, or a share of starts from S), over the maps of the study:

* the **IQM** of every run's share (the mean of the middle half), with a 95 % stratified
  bootstrap interval (seeds redrawn within each map);
* the **probability of improvement** of each method over each other: P(a run of X spends
  a smaller share than a run of Y), per map over all seed pairs (ties ½, "never" ties
  "never"), averaged over the maps, with its bootstrap interval;
* per map, the **winner**: the lowest median episodes to a stable optimal route (ties:
  more optimal seeds), with the median's bootstrap interval;
* the **performance profile** (:func:`figure_from_artifact`): the share of runs whose
  score is at most τ, for τ from 0 to 1, a curve per method.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from scenarios.artifacts import load_artifact
from scenarios.figures.mpl import pyplot
from scenarios.palette import method_colour_mpl
from scenarios.runs.statistics import (
    bootstrap_ci,
    probability_of_improvement_tasks,
    stratified_iqm,
)


def shares(episodes: list[int | None], budget: int) -> list[float]:
    """Each run's share of the budget before a stable optimal route (1.0: never)."""
    return [1.0 if e is None else min(1.0, e / budget) for e in episodes]


def _round(est: Any, digits: int = 3) -> list[float]:
    return [round(float(v), digits) if math.isfinite(v) else v for v in est]


def ranking(runs: dict[str, dict[str, list[int | None]]], budgets: dict[str, int],
            protocols: dict[str, str]) -> dict[str, Any]:
    """{"protocols": {protocol: {"order", "iqm", "poi", "maps"}}, "winners": {map: ...}}
    from ``runs[method][map]`` (episodes to a stable optimal route per seed, None: never),
    each map's episode ``budgets`` and its protocol."""
    methods = list(runs)
    out: dict[str, Any] = {"protocols": {}, "winners": {}}
    for proto in dict.fromkeys(protocols.values()):
        cols = [c for c in protocols if protocols[c] == proto
                and all(c in runs[m] for m in methods)]
        if not cols:
            continue
        score = {m: [shares(runs[m][c], budgets[c]) for c in cols] for m in methods}
        iqm = {m: _round(stratified_iqm(score[m])) for m in methods}
        poi = {m: {o: _round(probability_of_improvement_tasks(score[m], score[o]))
                   for o in methods if o != m} for m in methods}
        order = sorted(methods, key=lambda m: (iqm[m][0], m))
        out["protocols"][proto] = {"order": order, "iqm": iqm, "poi": poi, "maps": cols}
    for c in protocols:
        best = None
        for m in methods:
            eps = runs[m].get(c)
            if not eps:
                continue
            med = float(np.median([math.inf if e is None else e for e in eps]))
            key = (med, -sum(e is not None for e in eps))
            if best is None or key < best[0]:
                best = (key, m, eps)
        if best is not None:
            (med, neg_opt), m, eps = best
            lo, hi = bootstrap_ci(eps)
            out["winners"][c] = {"method": m, "optimal": -neg_opt, "seeds": len(eps),
                                 "median": med if math.isfinite(med) else None,
                                 "ci": [v if math.isfinite(v) else None for v in (lo, hi)]}
    return out


def profile(share: list[float], taus: np.ndarray) -> np.ndarray:
    """The share of runs whose score is at most each τ (a run that never got there, none)."""
    s = np.array([v if v < 1.0 else math.inf for v in share])
    return (s[None, :] <= taus[:, None]).mean(axis=1)


def figure_from_artifact(*names: str, path: Path) -> None:
    """The performance profiles of held-out artifacts: a panel per artifact and protocol."""
    plt = pyplot()

    panels: list[tuple[str, str, dict[str, Any], dict[str, Any]]] = []
    for name in names:
        d = load_artifact(name)["data"]
        if "ranking" not in d:  # written before the rankings: no seeds to draw from
            continue
        for proto, r in d["ranking"]["protocols"].items():
            panels.append((name.split(".", 1)[1], proto, d, r))
    cols = 2  # a row per study, a panel per protocol
    rows = -(-len(panels) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.9 * rows), squeeze=False)
    taus = np.geomspace(1e-3, 1.0, 301)  # log: S starts settle within a few % of the budget
    for ax, (label, proto, d, r) in zip(axes.ravel(), panels, strict=False):
        for m in r["order"]:
            runs = [v for c in r["maps"] for v in shares(d["runs"][m][c], d["budgets"][c])]
            ax.step(taus, profile(runs, taus), where="post", color=method_colour_mpl(m),
                    label=f"{m} (IQM {r['iqm'][m][0]:.2f})", lw=1.6)
        starts = "uniform starts" if proto == "uniform" else f"{proto[1:]} % of starts from S"
        ax.set_title(f"{label}, {starts} ({len(r['maps'])} maps)", fontsize=10)
        ax.set_xlabel("τ: share of the episode budget (log)")
        ax.set_xscale("log")
        ax.set_xlim(taus[0], 1)
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", framealpha=0.9)
    for row in axes:
        row[0].set_ylabel("share of runs optimal for good by τ")
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    fig.suptitle("Performance profiles on the held-out judging sets (higher and further "
                 "left is better)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

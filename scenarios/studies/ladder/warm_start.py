"""How much robot time does the grid save? Learn on the grid, finish at a physics rung.

    python -m scenarios.studies.ladder.warm_start --out results/warm-start --artifact study

For the ladder's four maps (open, rooms, maze, caves) at the rungs where the grid holds
(``noisy``) and where it breaks (``slip``, ``localised``), and for each method, three arms
on the same seeds (common random numbers):

(a) **the grid's policy driven at the rung**: trained ``--grid-episodes`` in the grid, no
    robot time (each warm run grades its carried policy before its first primitive);
(b) **trained at the rung from scratch** for each budget of ``--budgets`` episodes;
(c) **pretrained in the grid, then trained at the rung** for each budget (``pretrain=
    ("grid", n)``: the same grid phase as (a), then the rung's episodes);

and (d), **the multi-fidelity reference** (``mf-r-max``, Cutler et al.), is arm (c) of that
method. A budget's run is the first episodes of the longer budgets' runs (the same
streams), so the budgets trace one learning curve per seed, graded by the final policy's
50 drives at the rung. Every sweep is one :func:`scenarios.api.compare` call
(``OUT/MAP/RUNG/ARM-K/``); ``--resume`` keeps finished runs.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scenarios import api
from scenarios.artifacts import ROOT, load_artifact, write_artifact
from scenarios.artifacts.ladder import warm_start_table
from scenarios.figures.save import save_figure
from scenarios.palette import method_colour_mpl
from scenarios.runs.statistics import bootstrap_ci, quantile
from scenarios.script_args import arg, artifact_arg, jobs_arg, parse
from scenarios.studies.ladder.continuous_vs_grid import STUDY_MAPS, _map_path, _slug
from sim.files import atomic_write_text

PLAIN = "examples.script_own_learner:CountBonusQ"  # a plain-Python learner (Q + count bonus)
STUDY_METHODS = ("rnh-ql+", "haql", "dyna-q", PLAIN, "mf-r-max")
STUDY_RUNGS = ("noisy", "slip", "localised")
REACH_SLACK = 0.02  # one drive in 50: "reached (a)'s P(G)" allows the grading's granularity
MATERIAL = 0.05  # a P(G) difference below this is not called higher or lower: about one
#                  standard error of a 50-drive P(G) near 0.9 (sqrt(0.9 * 0.1 / 50) = 0.04)


@dataclass(frozen=True)
class Args:
    """Grid's policy at the rung (a), the rung from scratch (b), grid then rung (c), and
    the multi-fidelity reference (d): P(G) against robot primitives and seconds."""

    maps: str = arg(",".join(STUDY_MAPS), "scenarios (named, .toml, or KIND-N), comma-separated")
    methods: str = arg(",".join(STUDY_METHODS), "comma-separated")
    rungs: str = arg(",".join(STUDY_RUNGS), "physics rungs, comma-separated")
    seeds: int = arg(10, "seeds 0..N-1")
    grid_episodes: int = arg(300, "episodes in the grid before the rung (arms a, c, d)")
    budgets: str = arg("10,30,100,300", "episodes at the rung, comma-separated (the curve)")
    rewards: str = arg("goal-only", "reward scheme")
    jobs: int | None = jobs_arg()
    resume: bool = arg(False, "keep the runs of an earlier call")
    map_seed: int = arg(38, "generator seed of KIND-N maps")
    out: str = arg("results/warm-start", "output folder")
    artifact: str | None = artifact_arg("warm-start")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, Args.__doc__, argv)
    methods = _items(args.methods)
    budgets = sorted({int(b) for b in _items(args.budgets)})
    out = Path(args.out)
    cells = []
    for label in _items(args.maps):
        name = _map_path(label, args.map_seed, out)
        for rung in _items(args.rungs):
            for arm in ("scratch", "warm"):
                for k in budgets:
                    sub = out / _slug(label) / rung / f"{arm}-{k}"
                    print(f"{label} at {rung}, {arm}, {k} episodes -> {sub}", flush=True)
                    cmp = api.compare(name, methods, worlds="physics", fidelity=rung,
                                      seeds=args.seeds, episodes=k, rewards=args.rewards,
                                      jobs=args.jobs, out=sub, resume=args.resume,
                                      figures=False, progress=True,
                                      pretrain=("grid", args.grid_episodes)
                                      if arm == "warm" else None)
                    cells.append({"map": label, "rung": rung, "arm": arm, "budget": k,
                                  "runs": [dict(r.record) for r in cmp.runs]})
    data = study_data(cells, methods, budgets, args)
    atomic_write_text(out / "warm-start.md", "# How much robot time does the grid save?\n\n"
                      f"Command: `{data['command']}`\n\n" + warm_start_table(data))
    warm_start_figure(data, out / "warm-start.png")
    if args.artifact:
        write_artifact(f"warm-start.{args.artifact}", data["command"] + " --artifact "
                       + args.artifact, ["grid", "physics-noisy"], data, study=__file__)
        figure_from_artifact(f"warm-start.{args.artifact}", ROOT / "docs" / "warm-start.png")
    print(warm_start_table(data))
    return 0


def _items(text: str) -> list[str]:
    return [t.strip() for t in text.split(",") if t.strip()]


def command(args: Args) -> str:
    return (f"python -m scenarios.studies.ladder.warm_start --maps {args.maps} --methods "
            f"{args.methods} --rungs {args.rungs} --seeds {args.seeds} --grid-episodes "
            f"{args.grid_episodes} --budgets {args.budgets} --rewards {args.rewards} "
            f"--map-seed {args.map_seed}")


def _q(values: list[float]) -> list[float | None]:
    """median, q25, q75 (None for no values)."""
    return [quantile(values, q) for q in (0.5, 0.25, 0.75)] if values else [None] * 3


def _per_seed(cells: list[dict[str, Any]], m: str, rung: str, method: str
              ) -> dict[tuple[str, int], dict[int, dict[str, Any]]]:
    """(arm, budget) -> seed -> record, for one map, rung and method."""
    out: dict[tuple[str, int], dict[int, dict[str, Any]]] = {}
    for c in cells:
        if c["map"] == m and c["rung"] == rung:
            out[(c["arm"], c["budget"])] = {r["seed"]: r for r in c["runs"]
                                            if r["method"] == method}
    return out


def _stably_reached(curve: list[tuple[int, float]], target: float) -> int | None:
    """Robot primitives from which P(G) stays >= target at every later budget (None:
    it ends below)."""
    at = None
    for prims, p in curve:
        if p >= target - REACH_SLACK:
            at = prims if at is None else at
        else:
            at = None
    return at


def study_data(cells: list[dict[str, Any]], methods: list[str], budgets: list[int],
               args: Args) -> dict[str, Any]:
    """The artifact: one curve row per map x rung x method x arm x budget, and one summary
    row per map x rung x method (medians and quartiles over seeds; the warm-vs-better
    comparison paired by seed, with a bootstrap interval)."""
    maps = list(dict.fromkeys(c["map"] for c in cells))
    rungs = list(dict.fromkeys(c["rung"] for c in cells))
    curves, rows = [], []
    top = budgets[-1]
    for m in maps:
        for rung in rungs:
            for method in methods:
                by = _per_seed(cells, m, rung, method)
                seeds = sorted(by[("warm", top)])
                name = by[("warm", top)][seeds[0]]["method_name"]
                grid_p = {s: by[("warm", top)][s]["pretrain"]["policy"]["p_goal"] for s in seeds}
                grid_steps = [by[("warm", top)][s]["pretrain"]["env_steps"] for s in seeds]
                for arm in ("scratch", "warm"):
                    for k in budgets:
                        recs = [by[(arm, k)][s] for s in seeds]
                        curves.append({
                            "map": m, "rung": rung, "method": method, "arm": arm, "budget": k,
                            "p_goal": _q([r["final_policy"]["p_goal"] for r in recs]),
                            "primitives": _q([r["env_steps"] for r in recs]),
                            "seconds": _q([r["robot_seconds"] for r in recs])})
                curves_of = {}  # (arm, seed) -> [(robot primitives, P(G))], budgets in order
                for arm in ("scratch", "warm"):
                    for s in seeds:
                        pts = [(0, grid_p[s])] if arm == "warm" else []
                        curves_of[(arm, s)] = pts + [
                            (by[(arm, k)][s]["env_steps"],
                             by[(arm, k)][s]["final_policy"]["p_goal"]) for k in budgets]
                # the best P(G) any arm reached in the seed: a target (a) does not set alone
                best_p = {s: max(p for arm in ("scratch", "warm")
                                 for _, p in curves_of[(arm, s)]) for s in seeds}
                reach = {(arm, target): [_stably_reached(curves_of[(arm, s)], goal[s])
                                         for s in seeds]
                         for arm in ("scratch", "warm")
                         for target, goal in (("a", grid_p), ("best", best_p))}
                a = [grid_p[s] for s in seeds]
                b = [by[("scratch", top)][s]["final_policy"]["p_goal"] for s in seeds]
                c = [by[("warm", top)][s]["final_policy"]["p_goal"] for s in seeds]
                better = a if quantile(a, 0.5) >= quantile(b, 0.5) else b
                diff = [ci - bi for ci, bi in zip(c, better, strict=True)]
                lo, hi = bootstrap_ci(diff)
                best = {arm: max(((quantile([by[(arm, k)][s]["final_policy"]["p_goal"]
                                             for s in seeds], 0.5),
                                   quantile([by[(arm, k)][s]["env_steps"] for s in seeds], 0.5))
                                  for k in budgets), key=lambda t: (t[0], -t[1]))
                        for arm in ("scratch", "warm")}
                rows.append({
                    "map": m, "rung": rung, "method": method, "name": name,
                    "seeds": len(seeds), "grid_moves": _q(grid_steps),
                    "a_p_goal": _q(a), "b_p_goal": _q(b), "c_p_goal": _q(c),
                    "better_of_ab": "a" if better is a else "b",
                    "c_minus_better": [quantile(diff, 0.5), lo, hi],
                    "verdict": _verdict(quantile(diff, 0.5), lo, hi),
                    "best_p_goal": _q(list(best_p.values())),
                    "reach_warm": _reach(reach[("warm", "a")]),
                    "reach_scratch": _reach(reach[("scratch", "a")]),
                    "reach_best_warm": _reach(reach[("warm", "best")]),
                    "reach_best_scratch": _reach(reach[("scratch", "best")]),
                    "best_warm": list(best["warm"]), "best_scratch": list(best["scratch"]),
                    "b_primitives": _q([by[("scratch", top)][s]["env_steps"] for s in seeds]),
                    "c_primitives": _q([by[("warm", top)][s]["env_steps"] for s in seeds]),
                    "b_seconds": _q([by[("scratch", top)][s]["robot_seconds"] for s in seeds]),
                    "c_seconds": _q([by[("warm", top)][s]["robot_seconds"] for s in seeds])})
    return {"command": command(args), "budgets": budgets, "grid_episodes": args.grid_episodes,
            "reach_slack": REACH_SLACK, "material": MATERIAL, "curves": curves, "rows": rows}


def _verdict(median: float, lo: float, hi: float) -> str:
    """(c) against the better of (a) and (b): higher or lower only when the interval of the
    median difference excludes 0 and the difference is material (:data:`MATERIAL`)."""
    if lo <= 0.0 <= hi:
        return "no evidence of a difference"
    if abs(median) < MATERIAL:
        return "within the grading's resolution"
    return "higher" if lo > 0 else "lower"


def _reach(values: list[int | None]) -> dict[str, Any]:
    """Robot primitives to stably reach (a)'s P(G): median and quartiles over seeds, with
    ``never`` sorting last (None in the artifact), and how many seeds reached it."""
    q = _q([np.inf if v is None else float(v) for v in values])
    return {"q": [None if v is None or not np.isfinite(v) else v for v in q],
            "reached": sum(v is not None for v in values), "seeds": len(values)}


def figure_from_artifact(name: str, path: Path) -> None:
    """Draw the study's figure from artifact ``name`` (``rnhql report --figures``)."""
    warm_start_figure(load_artifact(name)["data"], path)


def warm_start_figure(data: dict[str, Any], path: Path) -> None:
    """P(G) at the rung against robot primitives, a panel per rung (rows) and map (columns):
    per method, dashed from scratch (b), solid pretrained in the grid (c; mf-r-max's is the
    multi-fidelity reference, d), the grid's policy (a) the solid line's point at 0."""
    # lazy: matplotlib costs 270 ms at import
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    curves, rows = data["curves"], data["rows"]
    maps = list(dict.fromkeys(r["map"] for r in rows))
    rungs = list(dict.fromkeys(r["rung"] for r in rows))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    names = {r["method"]: r["name"] for r in rows}
    fig, axes = plt.subplots(len(rungs), len(maps), figsize=(3.3 * len(maps), 2.7 * len(rungs)),
                             dpi=110, squeeze=False, sharey=True)
    for i, rung in enumerate(rungs):
        for j, m in enumerate(maps):
            ax = axes[i, j]
            for method in methods:
                colour = method_colour_mpl(method)
                for arm, ls in (("scratch", "--"), ("warm", "-")):
                    pts = [c for c in curves if c["map"] == m and c["rung"] == rung
                           and c["method"] == method and c["arm"] == arm]
                    x = [c["primitives"][0] for c in pts]
                    y = [c["p_goal"][0] for c in pts]
                    if arm == "warm":
                        row = next(r for r in rows if r["map"] == m and r["rung"] == rung
                                   and r["method"] == method)
                        x, y = [1.0, *x], [row["a_p_goal"][0], *y]
                    what = "grid, then rung" if arm == "warm" else "rung only"
                    ax.plot(x, y, ls=ls, color=colour, marker="o" if arm == "warm" else "s",
                            ms=2.8, lw=1.1, label=f"{names[method]} ({what})")
            ax.set_xscale("log")
            ax.set_ylim(-0.05, 1.05)
            ax.set_title(f"{m} at {rung}", fontsize=9)
            if j == 0:
                ax.set_ylabel("P(G), median of seeds")
            if i == len(rungs) - 1:
                ax.set_xlabel("robot primitives (median)")
            ax.tick_params(labelsize=7)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(5, len(labels)), fontsize=7,
               frameon=False, title="solid: pretrained in the grid (its first point, at 1 "
               "primitive: the grid's policy, no robot time); dashed: from scratch at the rung",
               title_fontsize=8)
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())

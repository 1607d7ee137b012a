"""The same methods and seeds in the grid and in physics, side by side.

    python -m scenarios.experiments.continuous_vs_grid paper-50 --methods rnh-ql,st-ql --seeds 3 \\
        --episodes 3000 --out results/cvg

Writes the usual ``results.json`` / ``summary.md`` / figures of a two-world
comparison, plus ``continuous_vs_grid.md`` (one row per method and world:
success, episodes to optimal, final route in cells and in metres driven,
contacts per episode, sim time to goal, wall time) and ``overlay.png`` (the
grid route and the physics trajectory on the map). Grid runs also *drive*
their final greedy policy in physics, so both worlds have driven figures.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from scenarios.experiments.compare import make_specs, run_sweep
from scenarios.figures.save import save_figure
from scenarios.runs.backends import Progress, run_local
from scenarios.runs.results import atomic_write_text
from scenarios.runs.spec import load


def _median(values: list[float | None], digits: int = 1, missing: str = "never") -> str:
    """Median by the one definition of :func:`scenarios.runs.results.quantile` (None sorts
    last, as never / not reached)."""
    from scenarios.runs.results import quantile

    if not values:
        return "—"
    v = quantile(values, 0.5)
    return missing if not np.isfinite(v) else f"{v:.{digits}f}"


def table(results: dict[str, Any]) -> str:
    rows = ["| method | world | seeds | optimum graded against | success rate | stable optimal "
            "after | final route (cells) | driven (m) | contacts on final drive | sim time to G "
            "(s) | contacts per training episode | wall time (s) |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in results["runs"]:
        groups.setdefault((r["method"], r["world"]), []).append(r)
    for (method, world), runs in groups.items():
        reached = [r for r in runs if r.get("physics_route_length", -1) >= 0]
        contacts = ("—" if world == "grid" else
                    f"{np.mean([np.mean(r['contacts_per_episode']) for r in runs]):.2f}")
        rows.append(
            f"| {method} | {world} | {len(runs)} | "
            f"{'physics' if world == 'physics' else 'grid'} "
            f"{runs[0].get('optimal_route_length', results['optimal_route_length'])} | "
            f"{_median([r['success_rate'] for r in runs], 3)} | "
            f"{_median([r['episodes_to_stable_optimal'] for r in runs], 0)} | "
            f"{_median([r['final_route_length'] if r['final_route_length'] >= 0 else None for r in runs], missing='no G')} | "  # noqa: E501
            f"{_median([r['physics_route_metres'] for r in reached])} | "
            f"{_median([r['physics_route_contacts'] for r in runs])} | "
            f"{_median([r['physics_route_sim_time_s'] for r in reached])} | {contacts} | "
            f"{_median([r['wall_time_s'] for r in runs], 2)} |")
    return "\n".join(rows)


def _physics_optimum(results: dict[str, Any]) -> str:
    vals = {r.get("physics_optimal_route_length") for r in results["runs"]} - {None}
    return "/".join(str(v) for v in sorted(vals)) if vals else "not computed"


def overlay_method(results: dict[str, Any], methods: list[str]) -> str:
    """The first method whose seed-0 policy reaches G when driven (else the first method)."""
    for m in methods:
        runs = [r for r in results["runs"] if r["method"] == m]
        first = min(runs, key=lambda r: (r["world"], r["seed"]))
        if first.get("physics_route_length", -1) >= 0:
            return m
    return methods[0]


def overlay(results: dict[str, Any], scenario: str, method: str, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from scenarios.figures.plots import draw_map
    from sim.planning import bfs_route

    sc, model = load(scenario)
    fig, ax = plt.subplots(figsize=(6.5, 6.5), dpi=110)
    draw_map(ax, sc, model)
    opt = model.coords[bfs_route(model.next_state, model.distance_to_goal, model.start)]
    ax.plot(opt[:, 0], opt[:, 1], color="#888888", lw=4, alpha=0.45,
            label=f"BFS optimum ({len(opt) - 1} moves)")
    styles = {"grid": ("#d9342b", "-"), "physics": ("#3c78e6", "-")}
    for world in ("grid", "physics"):
        runs = [r for r in results["runs"] if r["method"] == method and r["world"] == world]
        if not runs:
            continue
        run = min(runs, key=lambda r: r["seed"])
        colour, ls = styles[world]
        route = model.coords[np.asarray(run["final_route"], dtype=int)]
        if world == "grid":
            ax.plot(route[:, 0], route[:, 1], color=colour, lw=1.6, ls=ls,
                    label=f"grid-learned greedy route, seed {run['seed']}")
        xy = np.asarray(run.get("physics_route_xy", []))
        if len(xy):
            ax.plot(xy[:, 0], xy[:, 1], color=colour if world == "physics" else "#f08c00",
                    lw=1.0, ls="--" if world == "grid" else "-",
                    label=f"{world}-learned policy driven in physics "
                          f"({run['physics_route_metres']:.0f} m, "
                          f"{run['physics_route_contacts']} contacts)")
    ax.set_title(f"{sc.name}: {method}, grid vs physics", fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenario", nargs="?", default="paper-50")
    p.add_argument("--methods", default="rnh-ql,st-ql")
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--episodes", type=int, default=3000)
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--out", default="results/continuous-vs-grid")
    p.add_argument("--fidelity", default=None,
                   help="physics fidelity: exact (default), noisy, or knobs")
    args = p.parse_args(argv)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    specs = make_specs(args.scenario, methods, list(range(args.seeds)), args.episodes,
                       ["grid", "physics"], drive_final=True, fidelity=args.fidelity)
    out = Path(args.out)
    results = run_sweep(specs, out, run_local, jobs=args.jobs, progress=Progress(len(specs)))
    text = (f"# {results['scenario']['name']}: continuous vs gridded\n\n"
            "Command: `python -m scenarios.experiments.continuous_vs_grid "
            f"{args.scenario} --methods "
            f"{args.methods} --seeds {args.seeds} --episodes {args.episodes}`\n\n"
            f"Optima: grid BFS {results['optimal_route_length']} moves; physics BFS (over the "
            f"cell-to-cell moves the real disc drives) {_physics_optimum(results)} moves; "
            f"continuous (the disc's any-angle path, Theta* with exact line of sight: an "
            f"upper bound) {_continuous_optimum(results)} m. Physics fidelity: "
            f"`{results.get('fidelity') or 'exact'}`. "
            "Medians over seeds. Grid runs are graded against the grid optimum, physics runs "
            "against the physics optimum (greedy tests on the physics world's own model); "
            "`driven` columns drive the final greedy policy from S in physics (— when it never "
            "reached G).\n\n"
            + table(results) + "\n")
    atomic_write_text(out / "continuous_vs_grid.md", text)
    overlay(results, args.scenario, overlay_method(results, methods), out / "overlay.png")
    print(text)
    return 0


def _continuous_optimum(results: dict) -> str:
    vals = [r.get("continuous_optimal_route_m") for r in results["runs"]
            if r.get("continuous_optimal_route_m") is not None]
    return f"{vals[0]:.2f}" if vals else "—"


if __name__ == "__main__":
    sys.exit(main())

"""Continuous vs gridded along the fidelity ladder: where the grid abstraction holds.

    python -m scenarios.studies.ladder.continuous_vs_grid --out results/continuous-vs-grid

Maps (default: paper-40 open circles, rooms-1 rooms, maze-1 maze, caves-40 a generated
cave map) x rungs (exact, noisy, uncalibrated, open-loop, localised, latency, slip: see
:mod:`sim.physics.fidelity`) x methods x 10 seeds. At each rung every method is trained
in the grid (its final greedy policy then *driven* at the rung: transfer) and in physics
at the rung. Each (map, rung) is one ordinary comparison in ``OUT/MAP/RUNG/``
(``results.json``, ``summary.md``, figures, ``overlay.png``); ``OUT/ladder.md`` is the
one table (reached G, optimal routes, driven metres against the best method and against
the disc's continuous optimum, sim time, contacts, aliasing, V* where it is defined) and
the rank correlation of the methods, grid vs rung
(:mod:`scenarios.studies.ladder.predictivity`), and ``OUT/ladder.png`` the one figure.

A map is a built-in scenario, a ``.toml`` path, or ``KIND-N`` (a generated map of
:mod:`sim.maps.generators`, regenerated from ``--map-seed``; S and G the ends of its
diameter, as the held-out study makes them).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scenarios.artifacts import ROOT, load_artifact, write_artifact
from scenarios.artifacts.ladder import ladder_table
from scenarios.figures.plots import draw_map
from scenarios.figures.save import save_figure
from scenarios.palette import method_colour_mpl
from scenarios.runs.spec import RunSpec, load, make_config
from scenarios.runs.statistics import quantile
from scenarios.script_args import arg, artifact_arg, jobs_arg, parse, study_command
from scenarios.studies.ladder.predictivity import srcc
from scenarios.studies.maps.heldout import KIND, write_problem
from scenarios.sweep.execute import sweep
from sim.files import atomic_write_text
from sim.grid.planning import bfs_route
from sim.physics.fidelity import parse_fidelity
from sim.physics.models.optimum import continuous_optimum_m
from sim.scenario_io import builtin_names


def overlay_method(results: dict[str, Any], methods: list[str]) -> str:
    """The first method whose seed-0 policy reaches G when driven (else the first method)."""
    for m in methods:
        runs = [r for r in results["runs"] if r["method"] == m]
        first = min(runs, key=lambda r: (r["world"], r["seed"]))
        if first.get("final_policy", {}).get("p_goal", 0) > 0:
            return m
    return methods[0]


def overlay(results: dict[str, Any], scenario: str, method: str, path: Path) -> None:
    # lazy: matplotlib costs 270 ms at import, in each spawned sweep worker too
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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


STUDY_MAPS = ("paper-40", "rooms-1", "maze-1", "caves-40")  # open, rooms, maze, caves
STUDY_METHODS = ("rnh-ql+", "haql", "dyna-q", "q-lambda", "st-ql", "rnh-ql")
STUDY_RUNGS = ("exact", "noisy", "uncalibrated", "open-loop", "localised", "latency", "slip")


@dataclass(frozen=True)
class Args:
    """Methods x fidelity rungs x seeds on several maps, trained in the grid (and driven at
    every rung: transfer) and in physics at each rung; one table (ladder.md) and one figure
    (ladder.png). With --maps of one map and --rungs of one rung it is the old two-world
    comparison of that map."""

    maps: str = arg(",".join(STUDY_MAPS), "scenarios (named, or .toml paths), comma-separated")
    methods: str = arg(",".join(STUDY_METHODS), "comma-separated")
    rungs: str = arg(",".join(STUDY_RUNGS), "physics fidelities, comma-separated (presets; "
                     "knobs need their own run of `rnhql compare --fidelity`)")
    seeds: int = arg(10, "seeds 0..N-1 per method and rung")
    episodes: int = arg(300, "training episodes per run (a warm-up longer than a tenth of "
                        "them, rnh-ql's, is cut to a tenth: the paper's share)")
    rewards: str = arg("goal-only", "reward scheme")
    repeats: int = arg(10, "drives per (cell, action) for the aliasing column")
    jobs: int | None = jobs_arg()
    resume: bool = arg(False, "keep the runs of an earlier call")
    map_seed: int = arg(38, "generator seed of KIND-N maps (never one anything was tuned on)")
    out: str = arg("results/continuous-vs-grid", "output folder")
    artifact: str | None = artifact_arg("ladder")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, Args.__doc__, argv)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    maps = [m.strip() for m in args.maps.split(",") if m.strip()]
    rungs = [r.strip() for r in args.rungs.split(",") if r.strip()]
    out = Path(args.out)
    cells: list[dict[str, Any]] = []
    for label in maps:
        name = _map_path(label, args.map_seed, out)
        sc, model = load(name, rewards=args.rewards)
        for rung in rungs:
            specs = [spec for world in ("grid", "physics")
                     for spec in _rung_specs(name, methods, args, world, rung)]
            sub = out / _slug(label) / rung
            print(f"{label} at {rung}: {len(specs)} runs -> {sub}", flush=True)
            results = sweep(specs, sub, resume=args.resume, jobs=args.jobs)
            cells.append(dict(map=label, path=name, rung=rung, results=results,
                              aliasing=_aliasing(sc, model, rung, args.repeats),
                              predictivity=srcc(results["runs"], sc.steps_per_episode),
                              optimum=results.get("optimum_at_fidelity")))
            overlay(results, name, overlay_method(results, methods), sub / "overlay.png")
    text = ladder_report(cells, args)
    atomic_write_text(out / "ladder.md", text)
    data = ladder_data(cells, args)
    ladder_figure(data["rows"], methods, out / "ladder.png", data["rungs"])
    if args.artifact:  # the docs' table and figure, from the same data
        write_artifact(f"ladder.{args.artifact}", ladder_command(args),
                       ["grid", "physics-exact", "physics-noisy"], data, study=__file__)
        figure_from_artifact(f"ladder.{args.artifact}", ROOT / "docs" / "ladder.png")
    print(text)
    return 0


def figure_from_artifact(name: str, path: Path) -> None:
    """Draw the ladder's figure from artifact ``name`` (``rnhql report --figures``)."""
    d = load_artifact(name)["data"]
    methods = list(dict.fromkeys(r["method"] for r in d["rows"]))
    ladder_figure(d["rows"], methods, path, d.get("rungs"))


def _map_path(label: str, map_seed: int, out: Path) -> str:
    """A built-in name or .toml path as it is; ``KIND-N`` generated into ``OUT/maps``."""
    if label in builtin_names() or KIND.fullmatch(label) is None:
        return label
    toml, _, _ = write_problem(label, 0.0, map_seed, 0.0, out / "maps")
    return str(toml)


def _slug(name: str) -> str:
    return Path(name).stem if name.endswith(".toml") else name


def _rung_specs(name: str, methods: list[str], args: Args, world: str,
                rung: str) -> list[Any]:
    """Grid runs drive their final greedy policy at the rung (transfer); physics runs
    train and drive there."""
    return [RunSpec(scenario=name, method=m, seed=s, episodes=args.episodes, world=world,
                    rewards=args.rewards, drive_final=world == "grid",
                    fidelity=None if rung == "exact" else rung,
                    overrides=warmup_for_budget(m, args.episodes))
            for m in methods for s in range(args.seeds)]


WARMUP_SHARE = 0.1  # the paper's warm-up: 300 of 3000 episodes


def warmup_for_budget(method: str, episodes: int) -> tuple[tuple[str, float], ...]:
    """A method whose shaping waits out a warm-up of more than a tenth of the study's
    episodes (rnh-ql: 300) gets a tenth, the paper's share; otherwise, with the study's
    shorter budgets, it would never shape and be st-ql under another name."""
    warmup = getattr(make_config(method), "warmup_episodes", 0)
    share = round(WARMUP_SHARE * episodes)
    return (("warmup_episodes", float(share)),) if warmup > share else ()


def _aliasing(sc: Any, model: Any, rung: str, repeats: int) -> dict[str, float]:
    # lazy: the aliasing study imports matplotlib (270 ms), in each spawned sweep worker too
    from sim.physics.models.aliasing import measure_aliasing

    r = measure_aliasing(sc, model, parse_fidelity(rung), repeats=repeats)
    return {"multi_outcome_fraction": r["multi_outcome_fraction"],
            "mean_entropy_bits": r["mean_entropy_bits"]}


def _q(values: list[float], digits: int = 1) -> str:
    """median [q25, q75] of the values (— if none)."""
    if not values:
        return "—"
    m, lo, hi = (quantile(values, q) for q in (0.5, 0.25, 0.75))
    return f"{m:.{digits}f} [{lo:.{digits}f}, {hi:.{digits}f}]"


def ladder_rows(cells: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per map x rung x method x where it was trained (grid / the rung itself),
    from each run's ``final_policy``: the final greedy policy driven from S at the rung
    (once at exact, 50 times above it)."""
    rows = []
    optima: dict[str, float | None] = {}
    for cell in cells:
        res = cell["results"]
        if cell["map"] not in optima:
            sc, _ = load(cell.get("path", cell["map"]))
            optima[cell["map"]] = continuous_optimum_m(sc)
        cont = optima[cell["map"]]
        groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
        for r in res["runs"]:
            groups.setdefault((r["method"], r["world"]), []).append(r)
        for (method, world), runs in groups.items():
            pols = [r["final_policy"] for r in runs]
            metres = [p["metres_mean"] for p in pols if p["p_goal"] > 0]
            rows.append(dict(
                map=cell["map"], rung=cell["rung"], method=method,
                trained="grid" if world == "grid" else cell["rung"], seeds=len(runs),
                p_goal=[p["p_goal"] for p in pols],
                reliable=sum(p["p_goal"] >= 0.98 for p in pols),
                primitives=[p["primitives_mean"] for p in pols if p["p_goal"] > 0],
                metres=metres, ratio=[m / cont for m in metres] if cont else [],
                sim_time=[p["sim_time_s_mean"] for p in pols if p["p_goal"] > 0],
                contacts=[p["contacts_mean"] for p in pols],
                train_contacts=[float(np.mean(r["contacts_per_episode"])) for r in runs
                                if r.get("contacts_per_episode")],
                rollouts=pols[0]["rollouts"],
                physics_opt=runs[0].get("physics_optimal_route_length"),
                grid_opt=res["optimal_route_length"], cont=cont,
                aliasing=cell["aliasing"]["multi_outcome_fraction"]))
    return rows


def ladder_data(cells: list[dict[str, Any]], args: Args) -> dict[str, Any]:
    """The artifact the docs render the ladder table from (quantiles computed here)."""
    def q(v: list[float]) -> list[float | None]:
        return [quantile(v, x) for x in (0.5, 0.25, 0.75)] if v else [None] * 3

    rows = ladder_rows(cells)
    rungs = [{"map": c["map"], "rung": c["rung"], "predictivity": c["predictivity"],
              "optimum": c["optimum"]} for c in cells]
    out = []
    for r in rows:
        out.append({k: r[k] for k in ("map", "rung", "method", "trained", "seeds",
                                      "reliable", "rollouts", "aliasing", "grid_opt",
                                      "physics_opt", "cont")}
                   | {k: q(r[k]) for k in ("p_goal", "primitives", "metres", "ratio",
                                           "sim_time", "contacts", "train_contacts")})
    return {"command": ladder_command(args), "repeats": args.repeats, "rows": out,
            "rungs": rungs}


def ladder_command(args: Args) -> str:
    return study_command(__spec__.name, Args, args)


def ladder_report(cells: list[dict[str, Any]], args: Args) -> str:
    return ("# Continuous vs gridded, along the fidelity ladder\n\n"
            f"Command: `{ladder_command(args)}`\n\n" + ladder_table(ladder_data(cells, args)))


def ladder_figure(rows: list[dict[str, Any]], methods: list[str], path: Path,
                  rungs: list[dict[str, Any]] | None = None) -> None:
    """From the artifact's rows and rungs (:func:`ladder_data`). Left: how well the grid
    predicts each rung, Spearman's rho of the methods' order (deployed figure) with its
    bootstrap interval, a line per map. Right, per map: P(G) of each method's final policy
    driven at the rung (median over seeds), solid: trained at the rung, dashed: in the grid.
    """
    # lazy: matplotlib costs 270 ms at import, in each spawned sweep worker too
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    maps = list(dict.fromkeys(r["map"] for r in rows))
    rung_names = list(dict.fromkeys(r["rung"] for r in rows))
    x_of = {r: i for i, r in enumerate(rung_names)}
    fig, axes = plt.subplots(1, len(maps) + 1, figsize=(3.6 * (len(maps) + 1), 3.9), dpi=110,
                             squeeze=False)
    ax0 = axes[0, 0]
    for k, m in enumerate(maps):
        pts = [(x_of[c["rung"]], c["predictivity"]["deployed"]) for c in rungs or []
               if c["map"] == m and c["predictivity"]["deployed"]["rho"] is not None]
        if not pts:
            continue
        dx = (k - (len(maps) - 1) / 2) * 0.06
        x = [i + dx for i, _ in pts]
        y = [p["rho"] for _, p in pts]
        lo = [p["rho"] - p["ci95"][0] if p["ci95"] else 0 for _, p in pts]
        hi = [p["ci95"][1] - p["rho"] if p["ci95"] else 0 for _, p in pts]
        ax0.errorbar(x, y, yerr=[lo, hi], marker="o", ms=4, lw=1.2, capsize=2, label=m)
    ax0.axhline(0, color="#999999", lw=0.7)
    ax0.set_ylim(-1.05, 1.05)
    ax0.set_xticks(range(len(rung_names)), rung_names, rotation=30, fontsize=8)
    ax0.set_title("grid predicts the rung? SRCC", fontsize=10)
    ax0.set_ylabel("Spearman ρ, grid vs rung (deployed)")
    if ax0.get_legend_handles_labels()[0]:
        ax0.legend(fontsize=7, loc="lower left", frameon=False)
    else:
        ax0.text(0.5, 0.5, "undefined: no world tells\nthe methods apart", ha="center",
                 va="center", fontsize=8, transform=ax0.transAxes)
    for j, m in enumerate(maps, start=1):
        ax = axes[0, j]
        for method in methods:
            for physics in (False, True):
                pts = [(x_of[r["rung"]], r) for r in rows
                       if r["map"] == m and r["method"] == method
                       and (r["trained"] != "grid") == physics]
                if not pts:
                    continue
                pts.sort(key=lambda t: t[0])
                ax.plot([i for i, _ in pts], [r["p_goal"][0] for _, r in pts],
                        color=method_colour_mpl(method), ls="-" if physics else "--",
                        marker="o" if physics else "s", ms=3.5, lw=1.2,
                        label=method if physics else None)
        ax.set_title(f"{m}: P(G) of the final policy", fontsize=10)
        ax.set_ylim(-0.05, 1.05)
        ax.set_xticks(range(len(rung_names)), rung_names, rotation=30, fontsize=8)
    axes[0, 1].set_ylabel("P(G), median over seeds")
    handles, labels = axes[0, 1].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(methods), fontsize=8,
               frameon=False, title="solid: trained at the rung; dashed: trained in the grid",
               title_fontsize=8)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    save_figure(fig, path)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())

"""How episodes grow with the map: episodes to a stable optimal route against the free
cells, one map kind from 32² to 1024², beside an N log N line.

    python -m scenarios.studies.maps.growth --out results/growth --kind open \\
        --sizes 32,64,128,256,512,1024 --methods rnh-ql+explore,r-max --seeds 10
    python -m scenarios.studies.maps.growth --out /tmp/g --sizes 32,64 --seeds 2

Each size is a held-out problem (:func:`scenarios.studies.maps.heldout.write_problem`: the
map regenerated from ``--map-seed``, S and G the ends of its diameter, ``8 x the side``
episodes of ``max(600, 4 x the route)`` steps, goal-only rewards, the greedy test from S
every 10 episodes), under one protocol (``uniform`` or ``sP``). N is the number of free
cells with a route to G: the states a learner has to explore.

Why an N log N line: an explorer that must verify each of N states' moves before it can
trust a route needs on the order of N log N steps (Mormax's bound on an N-state map,
Szita & Szepesvári 2010, up to its factors in the horizon and accuracy); episodes of
length ``~ side`` then grow as ``N log N / side``. The artifact keeps every seed's
episodes; the figure (``docs/growth.png``, :func:`figure_from_artifact`) draws
the medians with their quartiles on log–log axes, and the table below gives each method's
exponent: the slope of a least-squares line through its log–log medians, over the sizes
where the median seed reached a stable optimal route.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scenarios.artifacts import check_artifact_name, load_artifact, write_artifact
from scenarios.artifacts.growth import growth
from scenarios.runs.spec import load
from scenarios.runs.statistics import quantile
from scenarios.script_args import arg, parse, parser_of, study_command
from scenarios.studies.maps.heldout import method_of, share_of, write_problem
from scenarios.sweep.backends import Progress, run_local
from scenarios.sweep.run import make_specs, run_sweep
from sim.files import atomic_write_text
from sim.maps.generators import KINDS


@dataclass(frozen=True)
class Args:
    out: str = arg("results/growth", "output folder")
    kind: str = arg("open", f"map kind ({', '.join(KINDS)}; maze: 4-cell corridors)")
    sizes: str = arg("32,64,128,256,512,1024", "comma-separated sides [cells]")
    methods: str = arg("rnh-ql+explore,r-max", "comma-separated methods, each "
                       "METHOD[:FIELD=V;FIELD=V]")
    protocol: str = arg("uniform", "uniform, or sP (P %% of episodes from S)")
    seeds: int = arg(10, "seeds per method and size (0 .. N-1)")
    map_seed: int = arg(7, "generator seed of the maps (7: the first tuning set's)")
    braid: float = arg(0.02, "share of a generated maze's inner walls knocked out")
    rewards: str = arg("goal-only", "reward scheme")
    jobs: int = arg(1, "worker processes")
    resume: bool = arg(False, "skip runs already finished in --out")
    artifact: str | None = arg(None, "also write docs/results/growth.NAME.json",
                               metavar="NAME")


def map_name(kind: str, size: int) -> str:
    """The held-out study's name of a generated map (a maze gets 4-cell corridors)."""
    return f"maze-w4-{size}" if kind == "maze" else f"{kind}-{size}"


def quartiles(values: list[int | None]) -> list[float | None]:
    """[q25, median, q75] of the seeds' episodes to a stable optimal route, a seed that never
    got there ranked last (:func:`scenarios.runs.statistics.quantile`, the sweeps' summary);
    a quartile that falls on or beside such a seed is None (never)."""
    out = [quantile(values, q) for q in (0.25, 0.5, 0.75)]
    return [None if math.isinf(v) else float(v) for v in out]


def exponent(cells: list[int], medians: list[float | None]) -> float | None:
    """Slope of log(median) against log(N) by least squares, over the sizes with a median
    (None with fewer than two)."""
    pts = [(n, m) for n, m in zip(cells, medians, strict=True) if m is not None and m > 0]
    if len(pts) < 2:
        return None
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def n_log_n(cells: list[int], sides: list[int]) -> tuple[list[float], list[float]]:
    """N log N (steps, Mormax's order) and N log N / side (the same in episodes of about a
    side's steps), per size."""
    steps = [float(n * np.log(n)) for n in cells]
    return steps, [v / s for v, s in zip(steps, sides, strict=True)]


def figure_from_artifact(name: str, path: str | Path) -> Path:
    """docs/growth.png from artifact ``growth.NAME``: each method's median episodes to a stable
    optimal route (bars: quartiles; a point only where the median seed got there) against
    N on log–log axes, with N log N and N log N / side drawn through the lowest median at
    the smallest N (their slopes are the point, not their height)."""
    from scenarios.figures.mpl import pyplot
    from scenarios.figures.save import save_figure
    from scenarios.palette import method_colour_mpl

    d = load_artifact(name)["data"]
    pts = d["points"]
    cells = [p["cells"] for p in pts]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    firsts = []
    for lab in d["methods"]:
        qs = [p["methods"][lab]["quartiles"] for p in pts]
        kept = [(n, q) for n, q in zip(cells, qs, strict=True) if q[1] is not None]
        if not kept:
            continue
        xs = [n for n, _ in kept]
        med = np.array([q[1] for _, q in kept])
        lo = med - np.array([q[0] if q[0] is not None else q[1] for _, q in kept])
        hi = np.array([q[2] if q[2] is not None else q[1] for _, q in kept]) - med
        slope = d["exponents"][lab]
        ax.errorbar(xs, med, yerr=[lo, hi], marker="o", capsize=3,
                    color=method_colour_mpl(lab),
                    label=lab + ("" if slope is None else f" (slope {slope:.2f})"))
        if xs[0] == cells[0]:
            firsts.append(med[0])
    if firsts:
        steps, per_side = n_log_n(cells, [p["size"] for p in pts])
        base = min(firsts)
        for ys, style, text in ((steps, ":", "∝ N log N"), (per_side, "--", "∝ N log N / side")):
            ax.plot(cells, base * np.array(ys) / ys[0], style, color="grey", label=text)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("free cells with a route to G, N")
    ax.set_ylabel("episodes to a stable optimal route")
    ax.set_title(f"{d['kind']} maps, {d['protocol']} starts, {d['seeds']} seeds "
                 f"(median, quartiles)", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return Path(path)


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    parser = parser_of(Args, __doc__)
    if args.artifact:
        check_artifact_name(parser, args.artifact)
    if args.kind not in KINDS:
        parser.error(f"--kind {args.kind!r}: give one of {', '.join(KINDS)}")
    try:
        share = share_of(args.protocol)
        sizes = sorted({int(s) for s in args.sizes.split(",") if s})
    except ValueError as e:
        parser.error(f"--protocol/--sizes: {e}")
    if not sizes or min(sizes) < 8:
        parser.error(f"--sizes {args.sizes!r}: give sides of at least 8 cells")
    out = Path(args.out)
    labels = [m for m in args.methods.split(",") if m]
    seeds = list(range(args.seeds))
    points: list[dict[str, Any]] = []
    for size in sizes:
        try:
            toml, route, episodes = write_problem(map_name(args.kind, size), share,
                                                  args.map_seed, args.braid, out / "maps")
        except ValueError as e:
            parser.error(f"--sizes {size} with --kind {args.kind}: {e} (give a larger side)")
        model = load(str(toml), s_starts=share)[1]
        cells = int((np.asarray(model.distance_to_goal) >= 0).sum())
        point: dict[str, Any] = {"size": size, "cells": cells, "route": route,
                                 "budget": episodes, "methods": {}}
        for label in labels:
            m, ov = method_of(label)
            specs = make_specs(str(toml), [m], seeds, episodes, ["grid"], overrides=ov,
                               rewards=args.rewards, s_starts=share)
            print(f"{args.kind}-{size} ({cells} cells): {label}: {len(specs)} runs",
                  file=sys.stderr)
            tag = "".join(c if c.isalnum() or c in "+.=-" else "_" for c in label)
            res = run_sweep(specs, out / toml.stem / tag, run_local, resume=args.resume,
                            figures=False, jobs=args.jobs, progress=Progress(len(specs)))
            done = sorted((r for r in res["runs"] if r["method"] == m and r["world"] == "grid"),
                          key=lambda r: r["seed"])
            eps = [r["episodes_to_stable_optimal"] for r in done]
            point["methods"][label] = {
                "episodes": eps, "quartiles": quartiles(eps),
                "optimal": sum(bool(r["final_route_optimal"]) for r in done),
                "wall_s": float(np.median([r["wall_time_s"] for r in done]))}
        points.append(point)
    data = {"kind": args.kind, "protocol": args.protocol, "seeds": args.seeds,
            "map_seed": args.map_seed, "rewards": args.rewards, "methods": labels,
            "points": points,
            "exponents": {lab: exponent([p["cells"] for p in points],
                                        [p["methods"][lab]["quartiles"][1] for p in points])
                          for lab in labels}}
    text = growth(data)
    atomic_write_text(out / "growth.md", text)
    if args.artifact:
        write_artifact(f"growth.{args.artifact}",
                       study_command("scenarios.studies.maps.growth", Args, args),
                       ["grid"], data, study=__file__)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

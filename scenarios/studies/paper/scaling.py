"""The paper's "larger state space" claim as a scaling study, not a two-point comparison.

    python -m scenarios.studies.paper.scaling --out results/scaling            # 10 seeds
    python -m scenarios.studies.paper.scaling --out /tmp/sc --seeds 2 --sizes 25,50  # a look

Arenas of n x n cells (n = 25, 50, 100, 200 by default) at paper-50's obstacle
density (28 circles of radius 1-3 m per 2,500 m^2, seeded), S and G near
opposite corners (3 cells in). The budget grows with the map and is stated in
the report: ``steps_per_episode = 12 n`` (600 at n = 50) and ``episodes = 60 n``
(3000 at n = 50). Goal-only rewards by default (under the paper's +1 per free
step no method finds the route at n = 50, see the reward-design experiment).

For each method: median [q25, q75] episodes to a stable optimal route and wall
time per run against the number of states, on log-log axes, with the fitted
growth exponent (slope of log median over log states, over the sizes where the
median is finite).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from scenarios.artifacts import ROOT, check_artifact_name, load_artifact, write_artifact
from scenarios.figures.scaling import figure
from scenarios.script_args import arg, parse, parser_of, study_command
from scenarios.sweep.execute import sweep
from scenarios.sweep.run import make_specs
from sim.files import atomic_write_text

DENSITY = 28 / 2500  # circles per m^2, as paper-50
METHODS = ("rnh-ql", "rnh-ql+", "st-ql", "q-lambda", "dyna-q")


def arena(n: int, folder: Path) -> Path:
    path = folder / f"scaling-{n}.toml"
    path.write_text(
        f'name = "scaling-{n}"\n'
        f'description = "{n}x{n} arena, paper-50 obstacle density, S/G near opposite corners"\n'
        f"start = [3, 3]\ngoal = [{n - 4}, {n - 4}]\nsteps_per_episode = {12 * n}\n"
        f"[arena]\nwidth_m = {n}.0\nheight_m = {n}.0\n"
        f"[obstacles.random]\ncount = {round(DENSITY * n * n)}\nradius_min_m = 1.0\n"
        f"radius_max_m = 3.0\nseed = {1000 + n}\n")
    return path


def fit_exponent(states: list[int], values: list[float | None]) -> float | None:
    """Slope of log(value) over log(states) where the value is finite (None: < 2 points)."""
    pts = [(math.log(s), math.log(v)) for s, v in zip(states, values, strict=True)
           if v is not None and v > 0]
    if len(pts) < 2:
        return None
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


@dataclass(frozen=True)
class Args:
    out: str = arg("results/scaling", "output folder: a folder per size, scaling.md, "
                   "scaling.png")
    sizes: str = arg("25,50,100,200", "arena sides n [cells], comma-separated")
    methods: str = arg(",".join(METHODS), "comma-separated methods")
    seeds: int = arg(10, "seeds per method and size (0 .. N-1)")
    rewards: str = arg("goal-only", "reward scheme (a preset, or goal=,bump=,step=)")
    jobs: int | None = arg(None, "worker processes [default: all cores]")
    resume: bool = arg(False, "skip runs already finished in --out")
    artifact: str | None = arg(None, "also write docs/results/scaling.NAME.json (the docs' "
                               "table) and redraw docs/scaling.png from it", metavar="NAME")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    if args.artifact:
        check_artifact_name(parser_of(Args, __doc__), args.artifact)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    sizes = [int(s) for s in args.sizes.split(",")]
    methods = [m for m in args.methods.split(",") if m]
    per_size: dict[int, dict[str, Any]] = {}
    for n in sizes:
        toml = arena(n, out)
        specs = make_specs(str(toml), methods, list(range(args.seeds)), 60 * n, ["grid"],
                           rewards=args.rewards)
        print(f"{n}x{n}: {len(specs)} runs", file=sys.stderr)
        per_size[n] = sweep(specs, out / f"n{n}", resume=args.resume, figures=False,
                            jobs=args.jobs)
    rows: dict[str, list[dict[str, Any]]] = {m: [] for m in methods}
    for n, res in per_size.items():
        states = n * n
        for m in methods:
            e = res["summary"][m]["grid"]
            rows[m].append({"n": n, "states": states, "episodes": e["episodes_to_stable_optimal"],
                            "wall": e["wall_time_s"], "optimal": e["optimal_route_fraction"],
                            "route": res["optimal_route_length"]})
    for pts in rows.values():
        fit = {k: fit_exponent([q["states"] for q in pts], [q[k]["median"] for q in pts])
               for k in ("episodes", "wall")}
        for q in pts:
            q["fit"] = {k: "n/a" if v is None else f"{v:.2f}" for k, v in fit.items()}
    title = (f"Scaling, rewards {args.rewards}: arenas {', '.join(f'{n}x{n}' for n in sizes)}, "
             f"steps/episode 12n, episodes 60n, {args.seeds} seeds")
    figure(rows, out / "scaling.png", title)
    command = study_command(__spec__.name, Args, args)
    if args.artifact:
        write_scaling_artifact(args, command, sizes, rows, title)
    lines = [f"# {title}", "", f"Command: `{command}`", "",
             "Cells: seeds whose final greedy route is optimal, median [q25, q75] episodes to a "
             "stable optimal route, median wall time per run. Exponent: slope of log median "
             "over log states (finite medians only).", "",
             "| method | " + " | ".join(
                 f"{q['n']}x{q['n']} ({q['states']} states, route {q['route']}, "
                 f"{60 * q['n']} episodes)" for q in rows[methods[0]])
             + " | exponent: episodes | exponent: wall time |",
             "|---|" + "---|" * (len(sizes) + 2)]

    def fmt(v: float | None) -> str:
        return "never" if v is None else f"{v:.0f}"

    for m, pts in rows.items():
        cells = [f"{round(q['optimal'] * args.seeds)}/{args.seeds} · "
                 f"{fmt(q['episodes']['median'])} [{fmt(q['episodes']['q25'])}, "
                 f"{fmt(q['episodes']['q75'])}] · {q['wall']['median']:.2f} s" for q in pts]
        lines.append(f"| {m} | " + " | ".join(cells) + f" | {pts[0]['fit']['episodes']} | "
                     f"{pts[0]['fit']['wall']} |")
    text = "\n".join(lines) + "\n"
    atomic_write_text(out / "scaling.md", text)
    print(text)
    return 0


def write_scaling_artifact(args: Args, command: str, sizes: list[int],
                           rows: dict[str, list[dict[str, Any]]], title: str) -> None:
    """``docs/results/scaling.NAME.json`` (the docs' table) and ``docs/scaling.png`` drawn
    from it (:func:`figure_from_artifact`)."""
    data = {"title": title, "sizes": sizes, "seeds": args.seeds, "rewards": args.rewards,
            "rows": rows}
    write_artifact(f"scaling.{args.artifact}", command, ["grid"], data, study=__file__)
    figure_from_artifact(f"scaling.{args.artifact}")


def figure_from_artifact(name: str, path: Path | None = None) -> Path:
    """Redraw ``docs/scaling.png`` (or ``path``) from artifact ``name``."""
    data = load_artifact(name)["data"]
    path = path or ROOT / "docs" / "scaling.png"
    figure(data["rows"], path, data["title"])
    return path


if __name__ == "__main__":
    sys.exit(main())

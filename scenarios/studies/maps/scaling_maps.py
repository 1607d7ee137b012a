"""Route learning on maps of 256 x 256 cells and more, of five kinds.

    python -m scenarios.studies.maps.scaling_maps --out results/scaling-maps       # 10 seeds
    python -m scenarios.studies.maps.scaling_maps --out /tmp/sm --seeds 2 --kinds city

Maps (:mod:`sim.maps.generators`, generator seed ``--map-seed``, not a
seed anything was tuned on): a city (``Berlin_1_256``, 2 x 2 per cell at 512), a
braided maze with 3-cell corridors, rooms of 15 cells with 1-3 cell doors, 20 %
random blocked cells, and caves (open areas, narrow passages). S and G are the
ends of a double BFS sweep (about the map's diameter). Budget: ``steps_per_episode
= max(600, 4 x the optimal route)``, ``episodes = 8 n`` (2048 at 256), goal-only
rewards.

Episode starts: uniform over free cells, as the paper, except that a share
``--s-starts`` (0.1) of episodes starts at S. Under uniform starts alone the
neighbourhood of S is rarely visited on a map of 50,000 cells, and a greedy test
from S dies a few moves out at cells the agent never saw, whatever the method (see
the README). ``--ablation`` adds rnh-ql+ rows with uniform starts only, without the
known-route test, and with prioritized sweeping (``sweeping=1``).

Cells of the table: seeds whose final greedy route is optimal, median [q25, q75]
episodes to a stable optimal route, median wall time per run.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

from scenarios.artifacts import check_artifact_name, write_artifact
from scenarios.runs.spec import load
from scenarios.script_args import script_parser
from scenarios.sweep.backends import Progress, run_local
from scenarios.sweep.run import make_specs, run_sweep
from sim.files import atomic_write_text
from sim.grid.planning import far_start_goal
from sim.maps.generators import KINDS, generate
from sim.maps.movingai import movingai_to_cell, write_free_grid

METHODS = ("rnh-ql+", "haql", "dyna-q")
# (label, method, overrides, uniform starts only)
ABLATION = {"uniform": ("rnh-ql+, random starts only", "rnh-ql+", (), True),
            "no-known": ("rnh-ql+, no known-route test", "rnh-ql+", (("known_route", 0.0),),
                         False),
            "sweeping": ("rnh-ql+, prioritized sweeping", "rnh-ql+", (("sweeping", 1.0),),
                         False)}


def write_problem(kind: str, size: int, seed: int, share: float, folder: Path
                  ) -> tuple[Path, Path, int]:
    """The map, and two scenario TOMLs (with ``share`` of starts at S, and uniform only)."""
    free = generate(kind, size, seed)
    folder.mkdir(parents=True, exist_ok=True)
    mp = folder / f"{kind}-{size}-s{seed}.map"
    write_free_grid(free, mp)
    (sr, sc), (gr, gc), route = far_start_goal(free)
    sx, sy = movingai_to_cell(sc, sr, size)
    gx, gy = movingai_to_cell(gc, gr, size)
    steps = max(600, 4 * route)
    paths = []
    for tag, sh in (("", share), ("-uniform", 0.0)):
        p = folder / f"{kind}-{size}{tag}.toml"
        p.write_text(f'name = "{kind}-{size}{tag}"\n'
                     f'description = "generated {kind}, {size}x{size}, map seed {seed}"\n'
                     f"start = [{sx}, {sy}]\ngoal = [{gx}, {gy}]\n"
                     f"steps_per_episode = {steps}\ns_start_share = {sh}\n\n"
                     f'[arena]\nmap = "{mp.resolve()}"\ncell_size_m = 1.0\n')
        paths.append(p)
    return paths[0], paths[1], route


def cell(stat: dict[str, Any], seeds: int) -> str:
    e = stat["episodes_to_stable_optimal"]

    def f(v: float | None) -> str:
        return "never" if v is None else f"{v:.0f}"

    return (f"{round(stat['optimal_route_fraction'] * seeds)}/{seeds} · {f(e['median'])} "
            f"[{f(e['q25'])}, {f(e['q75'])}] · {stat['wall_time_s']['median']:.1f} s")


def reachable_cells(toml: Path) -> int:
    """Free cells with a route to G: the states a learner can explore."""
    _, model = load(str(toml))
    return int((model.distance_to_goal >= 0).sum())


def point(row: str, method: str, ablation: bool, kind: str, size: int, route: int,
          states: int, stat: dict[str, Any]) -> dict[str, Any]:
    """One row's cell on one map, as the artifact keeps it (quartiles as q25, median, q75)."""
    e, w = stat["episodes_to_stable_optimal"], stat["wall_time_s"]
    seeds = int(stat["seeds"])
    return {"row": row, "method": method, "ablation": ablation, "kind": kind, "size": size,
            "route": route, "states": states, "seeds": seeds,
            "optimal": round(stat["optimal_route_fraction"] * seeds),
            "episodes": [e["q25"], e["median"], e["q75"]],
            "wall": [w["q25"], w["median"], w["q75"]]}


def main(argv: list[str] | None = None) -> int:
    p = script_parser(__doc__)
    p.add_argument("--out", default="results/scaling-maps", help="output folder")
    p.add_argument("--sizes", default="256", help="map sizes [cells a side], e.g. 256,512")
    p.add_argument("--kinds", default=",".join(KINDS), help="map kinds")
    p.add_argument("--methods", default=",".join(METHODS), help="methods")
    p.add_argument("--seeds", type=int, default=10, help="seeds per method and map")
    p.add_argument("--map-seed", type=int, default=7, help="generator seed of the maps")
    p.add_argument("--s-starts", type=float, default=0.1,
                   help="share of episodes starting at S (0: the paper's uniform starts)")
    p.add_argument("--ablation", action="store_true",
                   help="add rnh-ql+ rows: uniform starts only, without the known-route test, "
                        "with prioritized sweeping")
    p.add_argument("--ablation-rows", default=",".join(ABLATION), metavar="ROWS",
                   help=f"which --ablation rows, of {', '.join(ABLATION)}")
    p.add_argument("--rewards", default="goal-only", help="reward scheme")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: cores)")
    p.add_argument("--resume", action="store_true", help="skip runs already in --out")
    p.add_argument("--artifact", default=None, metavar="NAME",
                   help="also write docs/results/scaling-maps.NAME.json (the docs' table; "
                        "docs/scaling-maps.png is drawn from these artifacts)")
    args = p.parse_args(argv)
    if args.artifact:
        check_artifact_name(p, args.artifact)
    out = Path(args.out)
    sizes = [int(s) for s in args.sizes.split(",")]
    kinds = [k for k in args.kinds.split(",") if k]
    methods = [m for m in args.methods.split(",") if m]
    ablation_rows = [r for r in args.ablation_rows.split(",") if r]
    unknown = sorted(set(ablation_rows) - set(ABLATION))
    if unknown:
        p.error(f"--ablation-rows: unknown {unknown}; use some of {', '.join(ABLATION)}")
    jobs = args.jobs or os.cpu_count() or 1
    seeds = list(range(args.seeds))
    rows: dict[str, dict[str, str]] = {}
    columns = []
    points: list[dict[str, Any]] = []
    for n in sizes:
        for kind in kinds:
            main_toml, uniform_toml, route = write_problem(kind, n, args.map_seed, args.s_starts,
                                                           out / "maps")
            col = f"{kind} {n}² (route {route})"
            columns.append(col)
            episodes = 8 * n
            sweeps = [(None, main_toml, make_specs(str(main_toml), methods, seeds, episodes,
                                                   ["grid"], rewards=args.rewards))]
            if args.ablation:
                for label, m, ov, uniform in (ABLATION[r] for r in ablation_rows):
                    toml = uniform_toml if uniform else main_toml
                    sweeps.append((label, toml, make_specs(str(toml), [m], seeds, episodes,
                                                           ["grid"], overrides=ov,
                                                           rewards=args.rewards)))
            for i, (label, _toml, specs) in enumerate(sweeps):
                print(f"{col}{'' if label is None else ': ' + label}: {len(specs)} runs",
                      file=sys.stderr)
                res = run_sweep(specs, out / f"{kind}-{n}" / f"sweep{i}", run_local,
                                resume=args.resume, figures=False, jobs=jobs,
                                progress=Progress(len(specs)))
                for m in ([label] if label else methods):
                    key = m if label is None else specs[0].method
                    rows.setdefault(m, {})[col] = cell(res["summary"][key]["grid"], args.seeds)
                    points.append(point(m, key, label is not None, kind, n, route,
                                        reachable_cells(main_toml), res["summary"][key]["grid"]))
    title = (f"Route learning on {', '.join(f'{n}x{n}' for n in sizes)} maps: "
             f"{args.seeds} seeds, episodes 8n, steps/episode max(600, 4 x route), rewards "
             f"{args.rewards}, {args.s_starts:.0%} of episodes start at S")
    lines = [f"# {title}", "",
             f"Command: `python -m scenarios.studies.maps.scaling_maps --out {args.out} --sizes "
             f"{args.sizes} --kinds {args.kinds} --methods {args.methods} --seeds {args.seeds} "
             f"--map-seed {args.map_seed} --s-starts {args.s_starts}"
             f"{' --ablation' if args.ablation else ''}"
             + ("" if not args.ablation or args.ablation_rows == p.get_default("ablation_rows")
                else f" --ablation-rows {args.ablation_rows}") + "`", "",
             "Cells: seeds whose final greedy route is optimal · median [q25, q75] episodes to "
             "a stable optimal route · median wall time per run.", "",
             "| method | " + " | ".join(columns) + " |", "|---|" + "---|" * len(columns)]
    for m, cells in rows.items():
        lines.append(f"| {m} | " + " | ".join(cells.get(c, "–") for c in columns) + " |")
    text = "\n".join(lines) + "\n"
    atomic_write_text(out / "scaling-maps.md", text)
    if args.artifact:
        command = lines[2].removeprefix("Command: `").removesuffix("`")
        write_artifact(f"scaling-maps.{args.artifact}", f"{command} --artifact {args.artifact}",
                       ["grid"], {"title": title, "seeds": args.seeds, "columns": columns,
                                  "points": points}, study=__file__)
    print(text)
    return 0


if __name__ == "__main__":
    from sim.errors import InputError

    try:
        sys.exit(main())
    except InputError as err:  # one line naming the file, the field and the fix; exit 2
        print(f"scaling_maps: error: {err}", file=sys.stderr)
        sys.exit(2)

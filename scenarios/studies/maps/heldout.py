"""Held-out maps: a list of (map, protocol, method, seeds) runs, one table.

    python -m scenarios.studies.maps.heldout --out results/heldout --seeds 3 \\
        --problems maze-w4-256@s10,city-256@uniform --methods rnh-ql+,haql

A problem is ``MAP@PROTOCOL``. ``MAP`` is a generated map, regenerated from its seed
(``--map-seed``; the maps are never committed), or a Moving AI ``.map`` file:

* ``maze-wW-N``: an N x N maze of Moving AI's kind with corridors W cells wide and
  1-cell walls (:func:`sim.maps.generators.maze`, ``--braid`` of its inner walls
  knocked out: loops, several routes);
* ``KIND-N``: any other kind of :mod:`sim.maps.generators` (``city-256`` is Berlin);
* a path ending in ``.map``;
* a built-in scenario (``rnhql scenarios``: the suite's maps, e.g. ``paper-50``), run as
  it is (its S, G and steps per episode) for ``--suite-episodes`` episodes;
* a scenario ``.toml`` (e.g. Berlin with another S and G), run as it is for 8 x its
  side episodes.

S and G are the ends of the map's diameter (a double BFS sweep), the budget that of the
large-map study (:mod:`scenarios.studies.maps.scaling_maps`): ``8 x the side`` episodes
of ``max(600, 4 x the optimal route)`` steps, goal-only rewards. ``PROTOCOL`` is
``uniform`` (every episode from a uniformly drawn free cell: the paper's protocol) or
``sP`` (P % of the episodes from S, the rest uniform; ``s10`` is the study's).

A method is a CLI name with optional config overrides, ``rnh-ql+:sweeping=1``
(several joined by ``;``: ``rnh-ql+:a=1;b=2``). Runs go one at a time unless
``--jobs`` says otherwise.

Cells of the table: seeds whose final greedy route is optimal / seeds · median
episodes to a stable optimal route (never: the median seed never got there) · median
wall time per run. Under it, per protocol, the rankings of
:mod:`scenarios.studies.maps.ranking`: each method's IQM share of the episode budget with
its stratified bootstrap interval, the probability of improvement of each over each
other, and each map's winner; the artifact keeps every seed's episodes, which the
performance profiles (``docs/heldout-profiles.png``) are drawn from.

Each sweep's folder keeps of every run only what its summary reads
(:mod:`scenarios.sweep.kept`): a 512² half of a judging set is a few MB, not 500, and can
be kept and resumed on another machine (``docs/results/unfinished``).
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path
from shlex import quote
from typing import Any

from scenarios.artifacts import check_artifact_name, write_artifact
from scenarios.artifacts.heldout import heldout
from scenarios.runs.spec import load
from scenarios.script_args import arg, parse, parser_of
from scenarios.studies.maps.ranking import ranking
from scenarios.sweep.backends import Progress, run_local
from scenarios.sweep.kept import run_sweep  # each run kept as its summary reads it
from scenarios.sweep.run import make_specs
from sim.files import atomic_write_text
from sim.grid.planning import far_start_goal
from sim.maps.generators import KINDS, generate
from sim.maps.movingai import movingai_to_cell, read_free_grid, write_free_grid
from sim.scenario_io import builtin_names

PROBLEMS = "maze-w4-256@s10,city-256@uniform"
METHODS = "rnh-ql+,haql,dyna-q"
MAZE = re.compile(r"maze-w(\d+)-(\d+)")
KIND = re.compile(rf"({'|'.join(KINDS)})-(\d+)")
PROTOCOL = re.compile(r"uniform|s(\d+)")


@dataclass(frozen=True)
class Args:
    out: str = arg("results/heldout", "output folder")
    problems: str = arg(PROBLEMS, "comma-separated MAP@PROTOCOL; MAP: maze-wW-N (W-cell "
                        "corridors, N cells a side), KIND-N or a .map file; PROTOCOL: uniform "
                        "or sP (P %% of episodes from S)")
    methods: str = arg(METHODS, "comma-separated methods, each METHOD[:FIELD=V;FIELD=V]")
    seeds: int = arg(3, "seeds per method and problem (0 .. N-1)")
    map_seed: int = arg(37, "generator seed of the generated maps (not one anything was "
                            "tuned on)")
    braid: float = arg(0.02, "share of a generated maze's inner walls knocked out")
    suite_episodes: int = arg(3000, "episodes on a built-in scenario (the suite's budget)")
    rewards: str = arg("goal-only", "reward scheme")
    jobs: int = arg(1, "worker processes")
    resume: bool = arg(False, "skip runs already finished in --out")
    artifact: str | None = arg(None, "also write docs/results/heldout.NAME.json (a docs "
                                     "table, rendered by scenarios.artifacts)", metavar="NAME")


def problem_map(name: str, map_seed: int, braid: float) -> tuple[Any, str]:
    """(free[row, col], a file-name stem) of a problem's ``MAP``."""
    if name.endswith(".map"):
        return read_free_grid(Path(name)), Path(name).stem
    m = MAZE.fullmatch(name)
    if m:
        w, n = int(m[1]), int(m[2])
        return generate("maze", n, map_seed, corridor=w, braid=braid), \
            f"{name}-s{map_seed}-b{braid:g}"
    m = KIND.fullmatch(name)
    if m:
        return generate(m[1], int(m[2]), map_seed), f"{name}-s{map_seed}"
    raise ValueError(f"map {name!r}: give maze-wW-N, KIND-N (KIND one of "
                     f"{', '.join(KINDS)}) or a .map file")


def share_of(protocol: str) -> float:
    m = PROTOCOL.fullmatch(protocol)
    if m is None:
        raise ValueError(f"protocol {protocol!r}: give uniform or sP (P % of episodes from S)")
    return 0.0 if protocol == "uniform" else int(m[1]) / 100.0


def method_of(text: str) -> tuple[str, tuple[tuple[str, float], ...]]:
    """``rnh-ql+:a=1;b=2`` -> ("rnh-ql+", (("a", 1.0), ("b", 2.0)))."""
    name, _, rest = text.partition(":")
    ov = tuple((k.strip(), float(v)) for k, v in (kv.split("=") for kv in rest.split(";") if kv))
    return name, ov


def write_problem(name: str, share: float, map_seed: int, braid: float, folder: Path
                  ) -> tuple[Path, int, int]:
    """The map and its scenario TOML; (toml, optimal route, episodes)."""
    free, stem = problem_map(name, map_seed, braid)
    size = max(free.shape)
    folder.mkdir(parents=True, exist_ok=True)
    mp = folder / f"{stem}.map"
    write_free_grid(free, mp)
    (sr, sc), (gr, gc), route = far_start_goal(free)
    sx, sy = movingai_to_cell(sc, sr, free.shape[0])
    gx, gy = movingai_to_cell(gc, gr, free.shape[0])
    toml = folder / f"{stem}-s{round(share * 100)}.toml"
    toml.write_text(f'name = "{stem}"\ndescription = "held-out {name}"\n'
                    f"start = [{sx}, {sy}]\ngoal = [{gx}, {gy}]\n"
                    f"steps_per_episode = {max(600, 4 * route)}\ns_start_share = {share}\n\n"
                    f'[arena]\nmap = "{mp.resolve()}"\ncell_size_m = 1.0\n')
    return toml, route, 8 * size


def cell(stat: dict[str, Any], seeds: int) -> str:
    e = stat["episodes_to_stable_optimal"]["median"]
    return (f"{round(stat['optimal_route_fraction'] * seeds)}/{seeds} · "
            f"{'never' if e is None else f'{e:.0f}'} · {stat['wall_time_s']['median']:.1f} s")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    if args.artifact:
        check_artifact_name(parser_of(Args, __doc__), args.artifact)
    out = Path(args.out)
    problems = [p.partition("@") for p in args.problems.split(",") if p]
    labels = [m for m in args.methods.split(",") if m]
    seeds = list(range(args.seeds))
    columns, rows = [], {}
    per_seed: dict[str, dict[str, list[int | None]]] = {}
    budgets: dict[str, int] = {}
    protocols: dict[str, str] = {}
    for name, _, protocol in problems:
        share = share_of(protocol or "s10")
        if name in builtin_names() or name.endswith(".toml"):
            model = load(name, s_starts=share)[1]
            side = int(model.coords.max() - model.coords.min() + 1)  # 1 m cells
            scenario = name
            episodes = args.suite_episodes if name in builtin_names() else 8 * side
            route = int(model.distance_to_goal[model.start])
            stem = f"{Path(name).stem}-s{round(share * 100)}"
        else:
            toml, route, episodes = write_problem(name, share, args.map_seed, args.braid,
                                                  out / "maps")
            scenario, stem = str(toml), toml.stem
        col = f"{name} {protocol or 's10'} (route {route})"
        columns.append(col)
        budgets[col], protocols[col] = episodes, protocol or "s10"
        for label in labels:
            m, ov = method_of(label)
            specs = make_specs(scenario, [m], seeds, episodes, ["grid"], overrides=ov,
                               rewards=args.rewards, s_starts=share)
            print(f"{col}: {label}: {len(specs)} runs", file=sys.stderr)
            tag = re.sub(r"[^A-Za-z0-9+.=-]", "_", label)
            res = run_sweep(specs, out / stem / tag, run_local, resume=args.resume,
                            figures=False, jobs=args.jobs, progress=Progress(len(specs)))
            rows.setdefault(label, {})[col] = cell(res["summary"][m]["grid"], args.seeds)
            done = sorted((r for r in res["runs"] if r["method"] == m and r["world"] == "grid"),
                          key=lambda r: r["seed"])
            per_seed.setdefault(label, {})[col] = [r["episodes_to_stable_optimal"] for r in done]
    caption = (f"Rewards {args.rewards}, {args.seeds} seeds, map seed {args.map_seed}, maze "
               f"braid {args.braid:g}; cells: optimal seeds / seeds · median episodes to a "
               "stable optimal route · median wall time per run.")
    data = {"caption": caption, "columns": columns, "rows": rows, "runs": per_seed,
            "budgets": budgets, "protocols": protocols,
            "ranking": ranking(per_seed, budgets, protocols)}

    text = heldout(data)
    atomic_write_text(out / "heldout.md", text)
    if args.artifact:
        command = "python -m scenarios.studies.maps.heldout " + " ".join(
            f"--{k.replace('_', '-')} {quote(str(v))}" for k, v in vars(args).items()
            if v not in (None, False) and k not in ("artifact", "resume", "jobs"))
        write_artifact(f"heldout.{args.artifact}", f"{command} --artifact {args.artifact}",
                       ["grid"], data, study=__file__)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The route-learning map suite: seeded maze and rooms maps, Moving AI maps and the
built-ins, as scenario TOMLs with a chosen reward scheme, start and goal far apart.

``python -m scenarios.studies.maps.suite --out DIR`` writes ``DIR/maps/*.map`` (the generated
maps), ``DIR/*.toml`` (one scenario per suite map) and ``DIR/suite.json`` (name, kind, file,
optimal route, steps per episode, whether the map is held out from tuning).

* Maps: :func:`sim.maps.generators.small_maze` and ``small_rooms`` from each seed.
* Start and goal: :func:`sim.grid.planning.far_start_goal`, a double BFS sweep over
  the map's free cells, so the route is about the map's diameter.
* ``steps_per_episode`` = max(600, 4 x the optimal route): an episode from a random
  start can still reach the goal after exploring.
* Rewards default to ``goal-only`` (+100 goal, -1 bump, 0 free step).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scenarios.script_args import arg, parse
from sim.grid import build_model
from sim.grid.planning import far_start_goal
from sim.maps.generators import small_maze, small_rooms
from sim.maps.movingai import load_map, movingai_to_cell, read_free_grid, write_free_grid
from sim.scenario import REWARD_SCHEMES
from sim.scenario_io import builtin_dir, load_scenario

MAPS_DIR = builtin_dir() / "maps"  # shipped copies
BUILTIN = ("paper-40", "paper-50", "zigzag-50", "arena")
MOVINGAI = ("room-32-32-8", "random-64-64-20", "lak307d", "ost003d")
TUNE_SEEDS = (1, 2)
HELD_OUT_SEEDS = (101, 102)


def _toml(name: str, desc: str, map_path: Path, start, goal, steps: int,
          rewards: tuple[float, float, float], scheme: str) -> str:
    g, b, s = rewards
    h = load_map(map_path).height
    sx, sy = movingai_to_cell(start[1], start[0], h)  # (row, col) -> rnhql's y-up cell
    gx, gy = movingai_to_cell(goal[1], goal[0], h)
    return (f'name = "{name}"\ndescription = "{desc}"\nstart = [{sx}, {sy}]\n'
            f'goal = [{gx}, {gy}]\nsteps_per_episode = {steps}\n\n[arena]\n'
            f'map = "{map_path.resolve()}"\ncell_size_m = 1.0\n\n'
            f'[rewards]   # {scheme}\ngoal = {g}\nbump = {b}\nstep = {s}\n')


def _builtin_toml(name: str, rewards: tuple[float, float, float], scheme: str) -> str:
    text = (builtin_dir() / f"{name}.toml").read_text()
    text = text.replace('map = "maps/', f'map = "{builtin_dir()}/maps/')
    out, skip = [], False
    for line in text.splitlines():
        if line.startswith("[rewards]"):
            skip = True
            continue
        if skip and line.startswith("["):
            skip = False
        if not skip:
            out.append(line)
    g, b, s = rewards
    return "\n".join(out) + f"\n\n[rewards]   # {scheme}\ngoal = {g}\nbump = {b}\nstep = {s}\n"


def build_suite(out: Path, scheme: str = "goal-only", moving_ai: bool = True,
                held_out_seeds: tuple[int, ...] = HELD_OUT_SEEDS) -> list[dict]:
    """Write the suite into ``out``; returns its entries (also in ``out/suite.json``).
    ``held_out_seeds``: the generator seeds of the held-out maze and rooms maps (more
    seeds: more maps of those kinds nobody tuned on)."""
    rewards = REWARD_SCHEMES[scheme]
    out.mkdir(parents=True, exist_ok=True)
    (out / "maps").mkdir(exist_ok=True)
    entries: list[dict] = []

    def add(name: str, kind: str, text: str, held_out: bool = False) -> None:
        path = out / f"{name}.toml"
        path.write_text(text)
        model = build_model(load_scenario(path))
        opt = int(model.optimal_route_length)
        steps = max(600, 4 * opt)
        if f"steps_per_episode = {steps}" not in text:
            text = "\n".join(f"steps_per_episode = {steps}" if ln.startswith("steps_per_episode")
                             else ln for ln in text.splitlines()) + "\n"
            path.write_text(text)
        entries.append(dict(name=name, kind=kind, file=str(path.resolve()), optimal=opt,
                            steps_per_episode=steps, free_cells=int(len(model.start_states) + 1),
                            held_out=held_out))

    kinds = {"paper-40": "open", "paper-50": "open", "zigzag-50": "large obstacles",
             "arena": "rooms"}
    for name in BUILTIN:
        add(name, kinds[name], _builtin_toml(name, rewards, scheme))
    gens = [("maze", small_maze, "maze"), ("rooms", small_rooms, "rooms")]
    for seed in (*TUNE_SEEDS, *held_out_seeds):
        for prefix, gen, kind in gens:
            free = gen(seed)
            mp = out / "maps" / f"{prefix}-{seed}.map"
            write_free_grid(free, mp)
            s, g, _ = far_start_goal(free)
            add(f"{prefix}-{seed}", kind,
                _toml(f"{prefix}-{seed}", f"generated {prefix}, seed {seed}", mp, s, g, 600,
                      rewards, scheme), held_out=seed not in TUNE_SEEDS)
    if moving_ai:
        mkinds = {"room-32-32-8": "rooms", "random-64-64-20": "random obstacles",
                  "lak307d": "large obstacles", "ost003d": "large"}
        for name in MOVINGAI:
            mp = MAPS_DIR / f"{name}.map"
            s, g, _ = far_start_goal(read_free_grid(mp))
            add(name, mkinds[name], _toml(name, f"Moving AI {name}, far start and goal", mp, s,
                                          g, 600, rewards, scheme))
    (out / "suite.json").write_text(json.dumps(entries, indent=1))
    return entries


def shipped_suite_tomls() -> dict[str, tuple[str, np.ndarray | None]]:
    """The suite's maps as named scenarios, as shipped in ``sim/builtin`` (so
    ``rnhql train maze-1`` works): name -> (TOML text, generated map or None for a
    Moving AI map already shipped). The scenario's own rewards are the built-ins'
    default (pick a scheme with ``--rewards``); map paths are relative to the TOML."""
    out: dict[str, tuple[str, np.ndarray | None]] = {}

    def toml(name: str, desc: str, free: np.ndarray) -> str:
        s, g, d = far_start_goal(free)
        h = free.shape[0]
        (sx, sy), (gx, gy) = (movingai_to_cell(c, r, h) for r, c in (s, g))
        steps = max(600, 4 * int(d))
        return (f"# {desc}; written by scenarios.studies.maps.suite.shipped_suite_tomls.\n"
                f"# Cells in rnhql's frame (y up): S is Moving AI {s[::-1]}, G {g[::-1]}.\n"
                f'name = "{name}"\ndescription = "{desc}, start and goal far apart"\n'
                f"start = [{sx}, {sy}]\ngoal = [{gx}, {gy}]\n"
                f"steps_per_episode = {steps}\n\n[arena]\n"
                f'map = "maps/{name}.map"\ncell_size_m = 1.0\n')

    for seed in (*TUNE_SEEDS, *HELD_OUT_SEEDS):
        for prefix, gen in (("maze", small_maze), ("rooms", small_rooms)):
            free = gen(seed)
            out[f"{prefix}-{seed}"] = (toml(f"{prefix}-{seed}",
                                            f"generated {prefix} map, seed {seed}", free), free)
    for name in MOVINGAI:
        free = read_free_grid(MAPS_DIR / f"{name}.map")
        out[name] = (toml(name, f"Moving AI map '{name}'", free), None)
    return out


@dataclass(frozen=True)
class Args:
    out: str = arg("results/suite", "directory for maps and TOMLs")
    rewards: str = arg("goal-only", "reward scheme of the suite's TOMLs",
                       choices=sorted(REWARD_SCHEMES))
    no_moving_ai: bool = arg(False, "skip the Moving AI maps")


def main(argv: list[str] | None = None) -> int:
    a = parse(Args, __doc__, argv)
    for e in build_suite(Path(a.out), a.rewards, not a.no_moving_ai):
        print(f"{e['name']:18s} {e['kind']:17s} optimal {e['optimal']:4d}  "
              f"steps/episode {e['steps_per_episode']:5d}  free {e['free_cells']:6d}"
              f"{'  held out' if e['held_out'] else ''}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

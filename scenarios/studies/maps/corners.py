"""A held-out problem with S and G at opposite corners, written as a scenario the held-out
study runs as it is.

    python -m scenarios.studies.maps.corners --maps maze-w4-256,maze-w1-512 \\
        --map-seed 2027 --out results/fresh-maps

For each ``MAP`` (the held-out study's grammar: ``maze-wW-N``, ``KIND-N`` or a ``.map``)
it writes the map and ``STEM-corners.toml`` beside it: S the free cell nearest the top-left
corner, G the cell S reaches nearest the bottom-right one
(:func:`sim.grid.planning.corner_start_goal`), ``max(600, 4 x the optimal route)`` steps
an episode (the held-out study's). Pass the TOML to the held-out study as a problem,
``results/fresh-maps/maze-w4-256-s2027-b0.02-corners.toml@uniform``; it runs a scenario
file for 8 x its side episodes, the same budget as a generated map's, and the protocol
sets the share of episodes from S.

Why a file and not a grammar of the held-out study: its problems keep their meaning (the
diameter's ends), and the artifacts written with them keep their provenance.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from scenarios.script_args import arg, parse, parser_of
from scenarios.studies.maps.heldout import problem_map
from sim.files import atomic_write_text
from sim.grid.planning import corner_start_goal
from sim.maps.movingai import movingai_to_cell, write_free_grid

STEPS_PER_ROUTE_MOVE = 4  # steps an episode per move of the optimal route (at least 600)
MIN_STEPS = 600


@dataclass(frozen=True)
class Args:
    maps: str = arg("maze-w4-256", "comma-separated MAPs: maze-wW-N, KIND-N or a .map file")
    map_seed: int = arg(2027, "generator seed of the generated maps")
    braid: float = arg(0.02, "share of a generated maze's inner walls knocked out")
    out: str = arg("results/fresh-maps", "folder for the maps and their scenarios")


def write_corners(name: str, map_seed: int, braid: float, folder: Path) -> tuple[Path, int]:
    """The map and its corner-to-corner scenario TOML; (toml, optimal route in moves)."""
    free, stem = problem_map(name, map_seed, braid)
    folder.mkdir(parents=True, exist_ok=True)
    mp = folder / f"{stem}.map"
    write_free_grid(free, mp)
    (sr, sc), (gr, gc), route = corner_start_goal(free)
    sx, sy = movingai_to_cell(sc, sr, free.shape[0])
    gx, gy = movingai_to_cell(gc, gr, free.shape[0])
    toml = folder / f"{stem}-corners.toml"
    atomic_write_text(toml, f'name = "{stem}-corners"\n'
                      f'description = "held-out {name}, S and G at opposite corners"\n'
                      f"start = [{sx}, {sy}]\ngoal = [{gx}, {gy}]\n"
                      f"steps_per_episode = {max(MIN_STEPS, STEPS_PER_ROUTE_MOVE * route)}\n\n"
                      f'[arena]\nmap = "{mp.name}"\ncell_size_m = 1.0\n')
    return toml, route


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    for name in (m for m in args.maps.split(",") if m):
        try:
            toml, route = write_corners(name, args.map_seed, args.braid, Path(args.out))
        except ValueError as e:
            parser_of(Args, __doc__).error(f"--maps: {e}")  # exits 2
        print(f"{toml}: {name}, corner to corner, optimal route {route} moves")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""What building a scenario costs as the map grows: ``python -m scenarios.bench.build [--json]``.

For random arenas of 50 to 1024 cells a side at paper-50's obstacle density
(28 circles of radius 1-3 m per 2,500 m^2), for the shipped Moving AI maps and
for a 1024 x 1024 map tiled from Berlin_1_256: the time to resolve and validate
the scenario and build the tabular model (median of 3, each in a fresh
subprocess so caches and imports are not counted), its peak RSS, and the
physics world's reset time. Build time per cell should stay flat: the cost is
O(cells + circle area), never O(cells x circles).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from scenarios.script_args import arg, parse
from sim.grid.planning import far_start_goal
from sim.maps.movingai import read_free_grid
from sim.scenario_io import builtin_dir

MAPS = builtin_dir() / "maps"
DENSITY = 28 / 2500  # circles per m^2, as paper-50
SIZES = (50, 100, 200, 512, 1024)

_CHILD = """
import resource, sys, time
t0 = time.perf_counter()
from scenarios.runs.spec import load
t1 = time.perf_counter()
spec, start, goal = sys.argv[1], eval(sys.argv[2]), eval(sys.argv[3])
sc, model = load(spec, start, goal)
t2 = time.perf_counter()
from sim.physics.reference.world import PhysicsWorld
from sim.physics.static import PhysicsConfig
t3 = time.perf_counter()
PhysicsWorld(sc, PhysicsConfig())
t4 = time.perf_counter()
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(t2 - t1, t4 - t3, rss, model.n_states, model.optimal_route_length)
"""


def arena_toml(n: int, folder: Path) -> Path:
    path = folder / f"arena-{n}.toml"
    count = round(DENSITY * n * n)
    path.write_text(f'name = "arena-{n}"\nstart = [2, 2]\ngoal = [{n - 3}, {n - 3}]\n'
                    f"[arena]\nwidth_m = {n}.0\nheight_m = {n}.0\n"
                    f"[obstacles.random]\ncount = {count}\nradius_min_m = 1.0\n"
                    "radius_max_m = 3.0\nseed = 7\n")
    return path


def tiled_berlin(folder: Path) -> Path:
    rows = (MAPS / "Berlin_1_256.map").read_text().splitlines()[4:260]
    path = folder / "berlin-1024.map"
    path.write_text("type octile\nheight 1024\nwidth 1024\nmap\n"
                    + "\n".join([r * 4 for r in rows] * 4) + "\n")
    return path


def measure(spec: str, start=None, goal=None, repeats: int = 3) -> dict:
    runs = []
    for _ in range(repeats):
        out = subprocess.run([sys.executable, "-c", _CHILD, spec, repr(start), repr(goal)],
                             capture_output=True, text=True, check=True,
                             cwd=Path(__file__).resolve().parents[2])
        build, reset, rss, n, opt = out.stdout.split()
        runs.append((float(build), float(reset), float(rss), int(n), int(opt)))
    build = statistics.median(r[0] for r in runs)
    return {"cells": runs[0][3], "build_s": build, "us_per_cell": 1e6 * build / runs[0][3],
            "peak_rss_mb": max(r[2] for r in runs), "physics_reset_s":
            statistics.median(r[1] for r in runs), "optimal": runs[0][4]}


def run_bench() -> dict[str, dict]:
    out: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for n in SIZES:
            out[f"arena {n}x{n}, {round(DENSITY * n * n)} circles"] = measure(
                str(arena_toml(n, folder)))
        for name in ("lak307d", "ost003d", "Berlin_1_256"):
            free = read_free_grid(MAPS / f"{name}.map")
            (sr, sc), (gr, gc), _ = far_start_goal(free)  # (row, col)
            out[f"{name}.map"] = measure(str(MAPS / f"{name}.map"), (sc, sr), (gc, gr))
        out["Berlin tiled 1024x1024 .map"] = measure(str(tiled_berlin(folder)), (0, 0),
                                                     (1023, 1023))
    return out


@dataclass(frozen=True)
class Args:
    json: bool = arg(False, "print the figures as JSON, not a Markdown table")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    res = run_bench()
    if args.json:
        print(json.dumps(res, indent=1))
        return 0
    print("| map | cells | build (s) | µs per cell | peak RSS (MB) | physics reset (s) |")
    print("|---|---|---|---|---|---|")
    for name, r in res.items():
        print(f"| {name} | {r['cells']:,} | {r['build_s']:.3f} | {r['us_per_cell']:.2f} | "
              f"{r['peak_rss_mb']:.0f} | {r['physics_reset_s']:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

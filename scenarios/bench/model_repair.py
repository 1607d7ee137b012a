"""The cost of a new wall in the optimistic model: repair against a full BFS.

    python -m scenarios.bench.model_repair            # 256 and 512 cells a side

On generated maps of each kind (:mod:`sim.maps.generators`, seed 7, G at
one end of the diameter), the agent's free space starts empty (every move believed
free) and learns the map's walls one blocked move at a time, in a seeded random order,
as bumps would find them. Each new wall that changes a distance is handled twice, by
:func:`learning.parts.free_space.repair_distances` and by the full BFS it replaces; the
report gives, per map, how many walls changed a distance and the median and mean
microseconds a wall for each (results are checked equal along the way).
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass

import numpy as np

from learning.parts.free_space import bfs_distances, distances_change, repair_distances
from scenarios.script_args import arg, parse
from sim.grid.planning import far_start_goal
from sim.maps.generators import KINDS, generate


def neighbours(n: int) -> np.ndarray:
    idx = np.arange(n * n).reshape(n, n)  # [row, col], the map's own frame
    nb = np.full((n * n, 4), -1, np.int32)
    for a, (dr, dc) in enumerate(((-1, 0), (1, 0), (0, -1), (0, 1))):
        r, c = np.divmod(np.arange(n * n), n)
        rr, cc = r + dr, c + dc
        ok = (rr >= 0) & (rr < n) & (cc >= 0) & (cc < n)
        nb[ok, a] = idx[rr[ok], cc[ok]]
    return nb


def bench_map(free: np.ndarray, seed: int = 0, max_walls: int = 4000) -> dict:
    n = free.shape[0]
    nb = neighbours(n)
    flat = free.ravel()
    _, goal_rc, _ = far_start_goal(free)
    goal = goal_rc[0] * n + goal_rc[1]
    # the true walls: a move from a free cell to a blocked one (or off the map)
    walls = [(s, a) for s in np.flatnonzero(flat) for a in range(4)
             if nb[s, a] >= 0 and not flat[nb[s, a]]]
    order = np.random.default_rng(seed).permutation(len(walls))
    blocked = np.zeros((n * n, 4), np.bool_)
    dist = np.zeros(n * n, np.int32)
    queue = np.zeros(n * n, np.int32)
    ref = dist.copy()
    ref_q = queue.copy()
    bfs_distances(nb, blocked, dist, queue, goal)
    repair_distances(nb, blocked, dist.copy(), queue.copy(), goal, goal)  # compile
    t_rep: list[float] = []
    t_bfs: list[float] = []
    for i in order:
        s, a = walls[i]
        change = distances_change(nb, dist, blocked, s, a)
        blocked[s, a] = True
        if not change:
            continue
        t0 = time.perf_counter()
        repair_distances(nb, blocked, dist, queue, goal, s)
        t1 = time.perf_counter()
        bfs_distances(nb, blocked, ref, ref_q, goal)
        t2 = time.perf_counter()
        t_rep.append(t1 - t0)
        t_bfs.append(t2 - t1)
        if not np.array_equal(dist, ref):
            raise AssertionError("repair and BFS disagree")
        if len(t_rep) >= max_walls:
            break
    def stats(ts: list[float]) -> dict[str, float]:
        return {"median": float(np.median(ts)) * 1e6, "mean": float(np.mean(ts)) * 1e6}

    return {"walls_changing_a_distance": len(t_rep), "repair_us": stats(t_rep),
            "bfs_us": stats(t_bfs)}


@dataclass(frozen=True)
class Args:
    sizes: str = arg("256,512", "map sizes [cells a side]")
    kinds: str = arg(",".join(KINDS), "map kinds")
    walls: int = arg(2000, "walls timed per map (at most)")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    out = {}
    for n in (int(x) for x in args.sizes.split(",")):
        for kind in args.kinds.split(","):
            out[f"{kind}-{n}"] = bench_map(generate(kind, n, 7), max_walls=args.walls)
            print(kind, n, json.dumps(out[f"{kind}-{n}"]), flush=True)
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

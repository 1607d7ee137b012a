"""The physics world's own tabular model: which cell each primitive really reaches.

The grid model blocks a cell when the robot's disc plus a 5 cm clearance would
touch an obstacle; the real disc in Pymunk has no clearance, so it can enter
some cells the grid blocks, and its optimum can be shorter than the grid's BFS
route. Grading a physics-learned policy on the grid model would call a route
through such a cell "G not reached". So a physics run is graded on this model:
from S outward (breadth first over the cells the robot actually reaches), every
action is driven as a primitive from rest at the cell centre in a fresh world
(the env's reset), and the cell the discretiser reports is the next state; a
contact is a bump (the robot stays). The arrays have the grid model's shapes and
meaning (:class:`sim.grid.model.TabularModel`), so greedy tests and BFS distances work
on it unchanged. Cells never reached from S keep "stay" for every action.

Building it drives 4 primitives per reachable cell (paper-50: ~10k primitives,
a few seconds), so it is cached in-process and on disk
(``$XDG_CACHE_HOME/rnhql/physics-graph/<digest>.npz``; :mod:`sim.physics.models.disk_cache`
checks a file before it is used, rebuilds one that fails, and says so). This model's own
check (:func:`_check`): the array's shape and dtype, and that every move either stays or
reaches the neighbour in its direction (a primitive moves one cell at most).
``RNHQL_NO_DISK_CACHE=1`` turns the disk cache off.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from functools import lru_cache
from pathlib import Path

import numpy as np
import pymunk

from sim.grid.actions import ACTION_DELTAS, N_ACTIONS
from sim.grid.model import TabularModel, build_model, episode_starts
from sim.grid.planning import breadth_first, distances_to
from sim.physics.models import disk_cache
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

# 2: with its key and the SHA-256 of its content; 3: the digest of disk_cache
FORMAT = "rnhql-physics-graph-3"
CACHE = disk_cache.CacheKind("physics-graph", FORMAT, ("next_state",), "physics-model")


def cache_dir() -> Path:
    return disk_cache.cache_dir(CACHE)


def digest(sc: Scenario, config: PhysicsConfig) -> str:
    """What the graph depends on: the scenario's content, the physics config, pymunk."""
    fields = {k: v for k, v in dataclasses.asdict(sc).items()
              if k not in ("name", "source", "description", "rewards", "physics",
                           "s_start_share")}
    blob = json.dumps([FORMAT, pymunk.version, fields, dataclasses.asdict(config)],
                      sort_keys=True, default=repr)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def drive_transitions(sc: Scenario, config: PhysicsConfig) -> np.ndarray:
    """int32[nS, 4]: the state each primitive reaches from each cell reachable from S."""
    from sim.grid.discretiser import Discretiser
    from sim.physics.reference.controller import PrimitiveController
    from sim.physics.reference.world import PhysicsWorld

    model = build_model(sc)
    disc = Discretiser.from_scenario(sc)
    controller = PrimitiveController(sc, config)
    cast_cache: dict = {}
    n = model.n_states
    nxt = np.repeat(np.arange(n, dtype=np.int32)[:, None], 4, axis=1)
    world = None

    def drive(frontier: np.ndarray) -> np.ndarray:
        nonlocal world
        reached = []
        for s in frontier.tolist():
            if s == model.goal:
                continue
            x, y = disc.state_centre(s)
            for a in range(N_ACTIONS):
                # the robot at rest on the cell centre, as the env's reset puts it
                if world is None:
                    world = PhysicsWorld(sc, config, (x, y, 0.0), cast_cache=cast_cache)
                else:
                    world.respawn((x, y, 0.0))
                res = controller.run(world, a)
                t = s if res.bumped else int(res.state)
                nxt[s, a] = t
                reached.append(t)
        return np.array(reached, dtype=np.int64)

    breadth_first(n, model.start, drive)
    return nxt


def model_from_transitions(sc: Scenario, nxt: np.ndarray) -> TabularModel:
    """The tabular model of driven transitions, with the scenario's rewards."""
    grid = build_model(sc)
    goal = grid.goal
    nxt = nxt.astype(np.int32).copy()
    nxt[goal] = goal
    states = np.arange(nxt.shape[0])[:, None]
    rw = sc.rewards
    reward = rw.of_moves(nxt == states, nxt == goal).astype(np.float64)  # a stay is a bump
    reward[goal] = 0.0
    dist = distances_to(nxt, goal)
    start_states = episode_starts(np.flatnonzero(dist > 0), grid.start, sc.s_start_share)
    for arr in (nxt, reward, dist, start_states):
        arr.setflags(write=False)
    return dataclasses.replace(grid, next_state=nxt, reward=reward, distance_to_goal=dist,
                               start_states=start_states)


def moves_are_local(nxt: np.ndarray, nx: int, ny: int) -> bool:
    """Whether every transition stays put or reaches the neighbouring cell in the action's
    direction, inside the arena: what a primitive from rest at a cell centre can do."""
    n = nx * ny
    s = np.arange(n)
    ix, iy = s % nx, s // nx
    for a, (dx, dy) in enumerate(ACTION_DELTAS):
        tx, ty = ix + dx, iy + dy
        inside = (tx >= 0) & (tx < nx) & (ty >= 0) & (ty < ny)
        ok = (nxt[:, a] == s) | (inside & (nxt[:, a] == tx + ty * nx))
        if not ok.all():
            return False
    return True


def _check(arrays: disk_cache.Arrays, nx: int, ny: int) -> str | None:
    """Why cached transitions cannot be this scenario's model, or None (see the module's doc)."""
    nxt = arrays["next_state"]
    n = nx * ny
    if nxt.shape != (n, 4) or nxt.dtype != np.int32:
        return f"its transitions are not int32[{n}, 4]"
    if nxt.min() < 0 or nxt.max() >= n or not moves_are_local(nxt, nx, ny):
        return "a move goes beyond the neighbouring cell"
    return None


@lru_cache(maxsize=8)
def physics_model(sc: Scenario, config: PhysicsConfig | None = None) -> TabularModel:
    """The physics world's tabular model of ``sc`` (cached in-process and on disk)."""
    config = config or PhysicsConfig()
    arrays = disk_cache.cached(
        CACHE, digest(sc, config),
        lambda: {"next_state": drive_transitions(sc, config)},
        lambda a: _check(a, sc.nx, sc.ny), max_bytes=64 + 64 * sc.nx * sc.ny + 4096)
    return model_from_transitions(sc, arrays["next_state"])

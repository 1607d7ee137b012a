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
(``$XDG_CACHE_HOME/rnhql/physics-graph/<digest>.npz``, written atomically). A cache
file is an input like any other and is checked before it is used (:func:`_load`): its
format, the key it was built for, the SHA-256 of its array, the array's shape and dtype,
and that every move either stays or reaches the neighbour in its direction (a primitive
moves one cell at most). A file that fails any check, or does not load at all (truncated,
a folder, not a zip), is rebuilt and rewritten, never trusted: a tampered model would
grade a policy on moves the robot cannot make. ``RNHQL_NO_DISK_CACHE=1`` turns the disk
cache off.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path

import numpy as np
import pymunk

from sim.files import atomic_path
from sim.grid.actions import ACTION_DELTAS, N_ACTIONS
from sim.grid.model import TabularModel, build_model, episode_starts
from sim.grid.planning import breadth_first, distances_to
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

FORMAT = "rnhql-physics-graph-2"  # 2: with its key and the SHA-256 of its content


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "rnhql" / "physics-graph"


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
    from sim.physics.controller import PrimitiveController
    from sim.physics.world import PhysicsWorld

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


def content_digest(nxt: np.ndarray) -> str:
    """SHA-256 of the transition array as stored (dtype, shape and bytes)."""
    h = hashlib.sha256(f"{nxt.dtype.str}{nxt.shape}".encode())
    h.update(np.ascontiguousarray(nxt).tobytes())
    return h.hexdigest()


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


def _load(path: Path, key: str, nx: int, ny: int) -> np.ndarray | None:
    """The cached transitions of ``key`` in ``path``, or None when the file does not hold
    exactly what this build would write (see the module's doc)."""
    n = nx * ny
    try:
        if not path.is_file() or path.stat().st_size > 64 + 64 * n + 4096:
            return None  # a folder, a device, or far larger than n x 4 int32 can be
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:
            if set(data.files) != {"format", "key", "sha256", "next_state"}:
                return None
            if str(data["format"]) != FORMAT or str(data["key"]) != key:
                return None
            nxt = data["next_state"]
            stored = str(data["sha256"])
    except Exception:  # BadZipFile, a torn header, a folder ...: any failure rebuilds
        return None
    if nxt.shape != (n, 4) or nxt.dtype != np.int32 or stored != content_digest(nxt):
        return None
    if nxt.min() < 0 or nxt.max() >= n or not moves_are_local(nxt, nx, ny):
        return None
    return nxt


def _save(path: Path, key: str, nxt: np.ndarray) -> None:
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, format=np.array(FORMAT), key=np.array(key),
                 sha256=np.array(content_digest(nxt)), next_state=nxt)


@lru_cache(maxsize=8)
def physics_model(sc: Scenario, config: PhysicsConfig | None = None) -> TabularModel:
    """The physics world's tabular model of ``sc`` (cached in-process and on disk)."""
    config = config or PhysicsConfig()
    use_disk = os.environ.get("RNHQL_NO_DISK_CACHE", "") in ("", "0")
    key = digest(sc, config)
    path = cache_dir() / f"{key}.npz"
    nxt = _load(path, key, sc.nx, sc.ny) if use_disk else None
    if nxt is None:
        nxt = drive_transitions(sc, config)
        if use_disk:
            try:
                if path.is_dir() and not path.is_symlink():
                    import shutil

                    shutil.rmtree(path)  # a folder under the cache file's own name
                _save(path, key, nxt)
            except (OSError, ValueError):  # a read-only home, a device under the name: the
                pass  # in-process cache still works
    return model_from_transitions(sc, nxt)

"""Aliasing: how many next cells one (cell, action) can lead to at a fidelity.

:func:`measure_aliasing` drives every action from every cell that reaches G, ``repeats``
times, from the poses the robot can be in at that fidelity, all as the robots of batched
worlds (:class:`sim.physics.kernel.batch.RouteBatch`):

- at ``exact`` a primitive ends on the next cell centre to rounding, facing its cardinal
  direction, and a bump places the robot back on its centre: starts are the centres,
  headings the four cardinal directions (so every pair has one outcome, by construction);
- with wheel noise but no carried pose the robot ends within the controller's tolerance
  of a centre: starts are spread uniformly over that tolerance disc, headings over the
  four cardinal directions within the heading tolerance;
- with carried pose a contact leaves the robot anywhere: starts are spread uniformly over
  the cell (poses that would overlap an obstacle are redrawn), headings over the circle.

Each robot gets its own noise stream (spawned from ``seed``). What the ladder's states
cannot see is measured here: ``multi_outcome_fraction`` (share of pairs with more than one
next cell), the mean next-cell entropy and the bump probability.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from sim.grid import TabularModel
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.kernel.sweep import overlap_depth
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

MAX_REPEATS = 100_000  # drives per (cell, action)

BATCH = 1024  # robots per batched world


def _starts(sc: Scenario, batch: RouteBatch, cells: np.ndarray, fid: Fidelity,
            cfg: PhysicsConfig, rng: np.random.Generator) -> np.ndarray:
    """float64[n, 3] start poses for robots in ``cells`` (state indices)."""
    n = cells.size
    c = sc.cell_size_m
    cx = (cells % batch.nx + 0.5) * c
    cy = (cells // batch.nx + 0.5) * c
    if fid.is_exact:
        return np.stack([cx, cy, rng.integers(0, 4, n) * (math.pi / 2)], axis=1)
    if not fid.carried_pose:
        r = cfg.tolerance_m * np.sqrt(rng.random(n))
        phi = rng.uniform(0, 2 * math.pi, n)
        th = rng.integers(0, 4, n) * (math.pi / 2) + rng.uniform(-1, 1, n) * cfg.tolerance_rad
        return np.stack([cx + r * np.cos(phi), cy + r * np.sin(phi), th], axis=1)
    g = batch.geometry
    seen = np.zeros(len(g.circles) + len(g.boxes), dtype=np.int64)
    poses = np.zeros((n, 3))
    for i in range(n):
        for stamp in range(1, 1000):
            x = cx[i] + rng.uniform(-0.5, 0.5) * c
            y = cy[i] + rng.uniform(-0.5, 0.5) * c
            seen[:] = 0
            if overlap_depth(g.circles, g.walls, g.boxes, g.cell_m, g.nx, g.ny, g.start,
                             g.items, seen, stamp, batch.radius_m, x, y) <= 0.0:
                break
        else:  # pragma: no cover - a free cell always has a free pose near its centre
            x, y = cx[i], cy[i]
        poses[i] = (x, y, rng.uniform(-math.pi, math.pi))
    return poses


def measure_aliasing(sc: Scenario, model: TabularModel, fid: Fidelity, repeats: int = 20,
                     seed: int = 0) -> dict[str, Any]:
    """Next-cell counts of every (cell that reaches G, action) over ``repeats`` drives."""
    cfg = PhysicsConfig()
    cells = np.asarray(model.start_states, dtype=np.int64)
    pairs = np.repeat(np.arange(cells.size * 4), repeats)  # pair = cell_index * 4 + action
    rng = np.random.default_rng(seed)
    noise_seeds = np.random.SeedSequence(seed).spawn(1)[0]
    next_states = np.zeros(pairs.size, dtype=np.int64)
    bumped = np.zeros(pairs.size, dtype=bool)
    t0 = time.perf_counter()
    batch = RouteBatch(sc, min(BATCH, pairs.size), cfg, fidelity=fid, contact_records=False)
    active = np.zeros(batch.n, dtype=bool)
    actions = np.zeros(batch.n, dtype=np.int64)
    for lo in range(0, pairs.size, batch.n):
        chunk = pairs[lo:lo + batch.n]
        n = chunk.size
        poses = _starts(sc, batch, cells[chunk // 4], fid, cfg, rng)
        noisy = fid.wheel_noise > 0
        children = noise_seeds.spawn(n) if noisy else []
        for i in range(n):
            if noisy:
                batch.set_noise_rng(i, np.random.default_rng(children[i]))
            batch.place(i, *poses[i])
        active[:] = False
        active[:n] = True
        actions[:n] = chunk % 4
        out = batch.step(actions, active)
        next_states[lo:lo + n] = out.state[:n]
        bumped[lo:lo + n] = out.bumped[:n]
    elapsed = time.perf_counter() - t0
    per_pair: list[dict[str, Any]] = []
    multi = 0
    entropies = np.zeros(cells.size * 4)
    bump_p = np.zeros(cells.size * 4)
    for p in range(cells.size * 4):
        sl = slice(p * repeats, (p + 1) * repeats)
        values, counts = np.unique(next_states[sl], return_counts=True)
        probs = counts / repeats
        entropies[p] = float(-(probs * np.log2(probs)).sum())
        bump_p[p] = float(bumped[sl].mean())
        multi += values.size > 1
        per_pair.append({"state": int(cells[p // 4]), "action": int(p % 4),
                         "next": {str(int(v)): int(k) for v, k in zip(values, counts,
                                                                       strict=True)},
                         "bump_probability": bump_p[p]})
    return {"scenario": sc.name, "fidelity": fid.label, "repeats": repeats, "seed": seed,
            "pairs": cells.size * 4, "primitives": int(pairs.size),
            "seconds": round(elapsed, 3),
            "multi_outcome_fraction": multi / (cells.size * 4),
            "mean_entropy_bits": float(entropies.mean()),
            "mean_bump_probability": float(bump_p.mean()),
            "per_pair": per_pair, "_entropy": entropies, "_cells": cells}


def entropy_map(sc: Scenario, model: TabularModel, result: dict[str, Any]) -> np.ndarray:
    """float64[ny, nx]: each cell's largest next-cell entropy over its actions (nan: blocked
    or not reaching G)."""
    grid = np.full(model.n_states, np.nan)
    grid[result["_cells"]] = result["_entropy"].reshape(-1, 4).max(axis=1)
    return grid.reshape(sc.ny, sc.nx)

"""Aliasing: how many next cells one (cell, action) can lead to at a fidelity.

``rnhql aliasing SCENARIO --fidelity NAME --out DIR`` (or ``python -m
scenarios.studies.ladder.aliasing``) drives every action from every cell that reaches G,
``--repeats`` times, from the poses the robot can be in at that fidelity, all as the
robots of batched worlds (:class:`sim.physics.kernel.batch.RouteBatch`):

- at ``exact`` a primitive ends on the next cell centre to rounding, facing its cardinal
  direction, and a bump places the robot back on its centre: starts are the centres,
  headings the four cardinal directions (so every pair has one outcome, by construction);
- with wheel noise but no carried pose the robot ends within the controller's tolerance
  of a centre: starts are spread uniformly over that tolerance disc, headings over the
  four cardinal directions within the heading tolerance;
- with carried pose a contact leaves the robot anywhere: starts are spread uniformly over
  the cell (poses that would overlap an obstacle are redrawn), headings over the circle.

Each robot gets its own noise stream (spawned from ``--seed``). Written to ``DIR``:
``aliasing.json`` (``multi_outcome_fraction``: share of (cell, action) pairs with more
than one next cell; ``mean_entropy_bits`` of the next-cell distribution;
``bump_probability`` and the outcome counts per pair), ``aliasing.png`` (a heat map of
each cell's largest next-cell entropy over its four actions) and ``aliasing.rrd``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import rerun as rr

from scenarios.artifacts import load_artifact, write_artifact
from scenarios.figures.save import save_figure
from scenarios.recording.file import RecordingFile
from scenarios.runs.spec import load
from scenarios.script_args import arg, artifact_arg, parse, positional
from sim.errors import InputError
from sim.files import atomic_write_text
from sim.grid import TabularModel
from sim.physics.fidelity import Fidelity, parse_fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.kernel.sweep import overlap_depth
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

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


def heat_map(sc: Scenario, model: TabularModel, result: dict[str, Any]) -> np.ndarray:
    """float64[ny, nx]: each cell's largest next-cell entropy over its actions (nan: none)."""
    grid = np.full(model.n_states, np.nan)
    ent = result["_entropy"].reshape(-1, 4).max(axis=1)
    grid[result["_cells"]] = ent
    return grid.reshape(sc.ny, sc.nx)


def heat_map_figure(grid: np.ndarray, title: str, path: Path) -> None:
    """The heat map PNG: each cell's largest next-cell entropy (grey: blocked or not
    reaching G)."""
    matplotlib.use("Agg")

    fig, ax = plt.subplots(figsize=(6, 5.4))
    cmap = plt.get_cmap("magma").with_extremes(bad="0.75")  # blocked / not reaching G: grey
    im = ax.imshow(grid, origin="lower", cmap=cmap, vmin=0.0,
                   vmax=max(1.0, float(np.nanmax(grid)) if np.isfinite(grid).any() else 1.0))
    fig.colorbar(im, ax=ax, label="largest next-cell entropy over the 4 actions [bits]")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x [cells]  (grey: blocked or not reaching G)")
    ax.set_ylabel("y [cells]")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def write_artifact_of(name: str, command: str, sc: Scenario, model: TabularModel,
                      result: dict[str, Any]) -> None:
    """``docs/results/aliasing.NAME.json``: the summary figures and the heat map's cells
    (None: blocked or not reaching G), what the docs' table and figure are drawn from."""
    grid = heat_map(sc, model, result)
    keep = ("scenario", "fidelity", "repeats", "seed", "pairs", "primitives",
            "multi_outcome_fraction", "mean_entropy_bits", "mean_bump_probability")
    data = {k: result[k] for k in keep}
    data["heat_map"] = [[None if np.isnan(v) else round(float(v), 4) for v in row]
                        for row in grid]
    write_artifact(f"aliasing.{name}", command, ["physics-exact", "physics-noisy"], data,
                   study=__file__)


def figure_from_artifact(name: str, path: Path) -> None:
    """Redraw the heat map from artifact ``name`` (``rnhql report --figures``)."""
    d = load_artifact(name)["data"]
    grid = np.array([[np.nan if v is None else v for v in row] for row in d["heat_map"]])
    heat_map_figure(grid, f"{d['scenario']}, fidelity {d['fidelity']}: "
                    f"{100 * d['multi_outcome_fraction']:.1f} % of (cell, action) pairs alias",
                    path)


def write_outputs(out: Path, sc: Scenario, model: TabularModel, result: dict[str, Any]) -> None:
    matplotlib.use("Agg")

    out.mkdir(parents=True, exist_ok=True)
    public = {k: v for k, v in result.items() if not k.startswith("_")}
    atomic_write_text(out / "aliasing.json", json.dumps(public, indent=1))
    grid = heat_map(sc, model, result)
    heat_map_figure(grid, f"{sc.name}, fidelity {result['fidelity']}: "
                    f"{100 * result['multi_outcome_fraction']:.1f} % of (cell, action) pairs "
                    "alias", out / "aliasing.png")
    cmap = plt.get_cmap("magma").with_extremes(bad="0.75")
    with RecordingFile(out / "aliasing.rrd",
                       recording_name=f"aliasing {sc.name} {result['fidelity']}") as rec:
        vmax = max(1.0, float(np.nanmax(grid)) if np.isfinite(grid).any() else 1.0)
        rgba = cmap(np.ma.masked_invalid(np.flipud(grid)) / vmax)  # the PNG's colours
        rec.stream.log("aliasing/entropy_map",
                       rr.Image((255 * rgba[..., :3]).astype(np.uint8)))
        rec.stream.log("aliasing/summary", rr.TextDocument(
            f"fidelity {result['fidelity']}: multi_outcome_fraction "
            f"{result['multi_outcome_fraction']:.4f}, mean entropy "
            f"{result['mean_entropy_bits']:.4f} bits, mean bump probability "
            f"{result['mean_bump_probability']:.4f} ({result['repeats']} drives per pair). "
            "Map: each cell's largest next-cell entropy over its 4 actions, 0 (black) to "
            f"{vmax:g} bits (yellow); grey: blocked or not reaching G."))


@dataclass(frozen=True)
class Args:
    scenario: str = positional("a built-in name, a .toml or a .map (with --start/--goal)")
    out: str = arg(None, "output folder: aliasing.json, heat map PNG, recording (required)",
                   metavar="DIR", required=True)
    fidelity: str = arg("exact", "exact (default), a preset (noisy, slippery, uncalibrated, "
                        "open-loop, localised) or knobs")
    repeats: int = arg(20, "drives per (cell, action)")
    seed: int = arg(0, "noise and start-pose seed")
    rewards: str | None = arg(None, "reward scheme (does not change aliasing)")
    artifact: str | None = artifact_arg("aliasing")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    args = dataclasses.replace(args, out=Path(args.out))
    run(args)
    return 0


def run(args: argparse.Namespace) -> dict[str, Any]:
    if args.repeats < 1 or args.repeats > 10_000:
        raise InputError("command line", "--repeats", f"must be in 1..10000, got {args.repeats}",
                         "pass e.g. --repeats 20")
    fid = parse_fidelity(args.fidelity)
    sc, model = load(args.scenario, getattr(args, "start", None), getattr(args, "goal", None),
                     args.rewards)
    result = measure_aliasing(sc, model, fid, args.repeats, args.seed)
    write_outputs(args.out, sc, model, result)
    if getattr(args, "artifact", None):
        command = (f"rnhql aliasing {args.scenario} --fidelity {args.fidelity} --out {args.out}"
                   + ("" if args.repeats == 20 else f" --repeats {args.repeats}")
                   + ("" if args.seed == 0 else f" --seed {args.seed}")
                   + f" --artifact {args.artifact}")
        write_artifact_of(args.artifact, command, sc, model, result)
    print(f"{sc.name}, fidelity {result['fidelity']}: {result['pairs']} (cell, action) pairs x "
          f"{result['repeats']} drives in {result['seconds']:.1f} s; multi_outcome_fraction "
          f"{result['multi_outcome_fraction']:.4f}, mean entropy "
          f"{result['mean_entropy_bits']:.4f} bits, mean bump probability "
          f"{result['mean_bump_probability']:.4f}; wrote {args.out}/aliasing.json, "
          "aliasing.png, aliasing.rrd")
    return result


if __name__ == "__main__":
    raise SystemExit(main())

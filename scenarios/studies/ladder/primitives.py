"""What one primitive does at each rung of the ladder: its outcome, its time, where it ends.

    python -m scenarios.studies.ladder.primitives --artifact rungs

Robots of a batched world (:class:`sim.physics.kernel.batch.RouteBatch`) drive uniformly
random actions from random start cells, each with its own noise stream, carrying their
pose from move to move as the rung says, on each map and at each rung. Per (map, rung):

- how primitives end: reached the target (as far as the controller knows), bumped, or out
  of time (``PhysicsConfig.timeout_s``), and the simulated seconds one takes;
- the end pose of every primitive that did not bump, against the target cell's centre and
  the action's heading: along-track and cross-track [m], heading [rad] (the "offline
  replay error" of the reality-gap literature, one primitive at a time);
- (once) how a blind drive curves: a noise-free open-loop drive of one cell with a per-run
  wheel bias, its cross-track error against the continuous arc's of the same curvature
  (1 when each period's twist is held along its arc, as
  :func:`sim.physics.motion.held_twist_velocity` drives it);
- the bumper re-firing: P(a move bumps | the move before it bumped), against P(it bumps |
  the move before did not), and against the grid's count (the share of those moves the
  grid itself blocks, from the cell the robot is in). ``noisy`` is also run with
  ``bumper_release_m = 0``: the switch without hysteresis.

Why: the ladder study (:mod:`scenarios.studies.ladder.continuous_vs_grid`) says whether the
grid's ranking of methods holds at a rung; this says what the rung does to the moves the
methods are made of, with nothing learned in between.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from scenarios.artifacts import write_artifact
from scenarios.script_args import arg, artifact_arg, parse, study_command
from sim.grid import build_model
from sim.grid.actions import ACTION_HEADINGS
from sim.physics.fidelity import PRESETS, parse_fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario
from sim.scenario_io import resolve_scenario

DEFAULT_RUNGS = (*PRESETS, "noisy,bumper_release_m=0")


@dataclass(frozen=True)
class Args:
    maps: str = arg("paper-40,maze-1", "built-in scenarios or .toml paths, comma-separated")
    rungs: str = arg(";".join(DEFAULT_RUNGS), "fidelities, semicolon-separated (a preset, or "
                     "a preset and knobs: noisy,bumper_release_m=0)")
    robots: int = arg(256, "robots per (map, rung)")
    moves: int = arg(80, "random primitives per robot")
    seed: int = arg(0, "seeds the start cells, the actions and every robot's noise stream")
    artifact: str | None = artifact_arg("primitives")


def _quartiles(x: np.ndarray) -> list[float] | None:
    """[median, q25, q75] (the tables' order), None when there is nothing to measure."""
    if x.size == 0:
        return None
    return [float(v) for v in np.quantile(x, [0.5, 0.25, 0.75])]


def _share(hits: np.ndarray, of: np.ndarray) -> float | None:
    n = int(of.sum())
    return float((hits & of).sum() / n) if n else None


def drive(map_name: str, rung: str, robots: int, moves: int, seed: int) -> dict[str, Any]:
    """Drive ``robots`` x ``moves`` random primitives on one map at one rung; the figures."""
    sc = resolve_scenario(map_name)
    model = build_model(sc)
    fid = parse_fidelity(rung)
    cfg = PhysicsConfig()
    batch = RouteBatch(sc, robots, cfg, fidelity=fid, contact_records=False)
    rng = np.random.default_rng(seed)
    streams = np.random.SeedSequence(seed).spawn(robots)
    starts = rng.choice(model.start_states, robots)
    for i in range(robots):
        batch.set_noise_rng(i, np.random.default_rng(streams[i]))
        batch.place(i, *batch.disc.state_centre(int(starts[i])), 0.0)
    r = batch.r
    shape = (moves, robots)
    reached, bumped, timeout = (np.zeros(shape, bool) for _ in range(3))
    grid_blocked = np.zeros(shape, bool)
    on_free = np.zeros(shape, bool)
    seconds = np.zeros(shape)
    along, cross, heading = (np.zeros(shape) for _ in range(3))
    free = ~model.blocked.ravel()
    for k in range(moves):
        actions = rng.integers(0, 4, robots)
        cells = np.asarray(r.state, dtype=np.int64)  # the cell each robot believes it is in
        cells = np.where(k == 0, starts, cells)
        on_free[k] = free[cells]
        grid_blocked[k] = model.next_state[cells, actions] == cells
        out = batch.step(actions)
        reached[k], bumped[k], timeout[k] = out.reached, out.bumped, out.timeout
        seconds[k] = out.steps * cfg.dt_s
        dx, dy = r.x - r.tx, r.y - r.ty
        c, s = np.cos(r.head), np.sin(r.head)
        along[k], cross[k] = dx * c + dy * s, -dx * s + dy * c
        heading[k] = (r.th - r.head + math.pi) % (2 * math.pi) - math.pi
    after_bump = np.zeros(shape, bool)
    after_bump[1:] = bumped[:-1]
    after_move = np.zeros(shape, bool)
    after_move[1:] = ~bumped[:-1]
    ended = ~bumped
    return {
        "map": sc.name, "rung": fid.label, "preset": rung, "primitives": int(bumped.size),
        "reached": float(reached.mean()), "bumped": float(bumped.mean()),
        "timeout": float(timeout.mean()),
        "seconds": _quartiles(seconds.ravel()),
        "end_along_m": _quartiles(along[ended]), "end_cross_m": _quartiles(cross[ended]),
        "end_heading_rad": _quartiles(heading[ended]),
        "end_cross_p95_m": float(np.quantile(np.abs(cross[ended]), 0.95)),
        "end_heading_p95_rad": float(np.quantile(np.abs(heading[ended]), 0.95)),
        "rebump": _share(bumped, after_bump), "bump_after_move": _share(bumped, after_move),
        "grid_blocks_after_bump": _share(grid_blocked, after_bump & on_free),
        "moves_after_bump": int(after_bump.sum()),
    }


def blind_arc(robots: int, seed: int) -> dict[str, Any]:
    """A noise-free open-loop drive of one cell (1 m) with a 2 % wheel-ratio bias, from a
    centre in free space: its cross-track error over the continuous arc's, ``(1 - cos(k L))
    / k`` for the curvature ``k = (g_r - g_l) / (b E_b)`` the bias gives (quartiles over
    robots; 1 would be the arc, below 1 an optimistic drive)."""
    sc = Scenario(name="open", width_m=12.0, height_m=12.0, start=(2, 6), goal=(9, 6))
    fid = parse_fidelity("open_loop=true,carried_pose=true,wheel_ratio_sigma=0.02")
    batch = RouteBatch(sc, robots, PhysicsConfig(), fidelity=fid, contact_records=False)
    streams = np.random.SeedSequence(seed).spawn(robots)
    x0, y0 = 4.5, 6.5
    for i in range(robots):
        batch.set_noise_rng(i, np.random.default_rng(streams[i]))
        batch.place(i, x0, y0, 0.0)
    batch.step(np.full(robots, ACTION_HEADINGS.index(0.0)))
    base, length = sc.robot.wheel_base_m, sc.cell_size_m
    ratios = []
    for i in range(robots):
        g_l, g_r, e_b = batch.bias(i)
        k = (g_r - g_l) / (base * e_b)
        arc = (1.0 - math.cos(k * length)) / k
        ratios.append((batch.pose(i)[1] - y0) / arc)
    return {"robots": robots, "length_m": length, "cross_track_over_arc":
            _quartiles(np.array(ratios))}


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    maps = [m.strip() for m in args.maps.split(",") if m.strip()]
    rungs = [r.strip() for r in args.rungs.split(";") if r.strip()]
    rows = []
    for map_name in maps:
        for rung in rungs:
            row = drive(map_name, rung, args.robots, args.moves, args.seed)
            rows.append(row)
            print(f"{row['map']} {rung}: reached {row['reached']:.3f} bumped "
                  f"{row['bumped']:.3f} timeout {row['timeout']:.3f} re-bump "
                  f"{row['rebump']} grid {row['grid_blocks_after_bump']}", flush=True)
    arc = blind_arc(args.robots, args.seed)
    print(f"blind drive: cross-track over the arc's {arc['cross_track_over_arc']}", flush=True)
    if args.artifact:
        write_artifact(f"primitives.{args.artifact}", study_command(__spec__.name, Args, args),
                       ["physics-exact",
                                                                 "physics-noisy"],
                       {"rows": rows, "robots": args.robots, "moves": args.moves,
                        "blind_arc": arc,
                        "timeout_s": PhysicsConfig().timeout_s}, study=__file__)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

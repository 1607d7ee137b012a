"""``rnhql route``: a saved agent's greedy route from S against the BFS optimum.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from learning.compiled.readout import greedy_actions, potential, q_table
from learning.drivers.checkpoint import load_checkpoint
from learning.drivers.train import greedy_test
from learning.geometry import geometry_of
from scenarios.cli.args import (
    check_world,
    compile_notice,
    physics_budget,
    problem_arg,
)
from scenarios.figures.routes import ascii_routes, route_png
from scenarios.runs.physics_grading import FINAL_ROLLOUTS, FINAL_TAG
from scenarios.runs.spec import layout_digest
from scenarios.sweep.outdir import check_output_file, record_path
from sim.grid.planning import bfs_route
from sim.physics.fidelity import parse_fidelity
from sim.physics.models.rollouts import drive_policy


def cmd_route(args: argparse.Namespace) -> int:
    pb = problem_arg(args)
    sc, model = pb.sc, pb.model
    check_world(args.world)
    physics_budget(sc, [args.world])
    if args.png:
        check_output_file(Path(args.png), "--png", ".png")
    ckpt = load_checkpoint(args.agent, None, model.n_states, geometry_of(model))
    # an agent trained on another scenario of the same size loads; its route here would
    # mean nothing. The layout is checked, not the rewards or starts: a route ignores them
    ckpt.check_problem({"layout": layout_digest(pb.scenario, pb.start, pb.goal)})
    optimum = bfs_route(model.next_state, model.distance_to_goal, model.start)
    length, route = greedy_test(ckpt.state, model)
    trajectory = driven = None
    print(f"{ckpt.config.name} agent {args.agent} ({ckpt.episodes} episodes) on {sc.name}")
    if args.world == "physics":
        compile_notice(0, physics=True)

        fid = pb.fidelity or parse_fidelity(sc.physics)
        n = 1 if fid.is_exact else FINAL_ROLLOUTS
        driven = drive_policy(sc, greedy_actions(ckpt.state), fid, n, 0, FINAL_TAG,
                              measure_metres=True, keep_routes=True, keep_path=True)
        route, trajectory = driven.routes[0], driven.path[:, :2]
        length = len(route) - 1 if driven.reached[0] else -1
        lo, hi = driven.p_goal_interval
        print(f"  driven in physics at {fid.label}: P(G) {driven.p_goal:.2f} "
              f"[{lo:.2f}, {hi:.2f}] over {n} drive(s); the drive shown "
              f"{'reached G' if driven.reached[0] else 'did not reach G'}, "
              f"{driven.metres[0]:.1f} m, {int(driven.contacts[0])} contacts, "
              f"{driven.sim_time_s[0]:.1f} s sim time")
    record = record_path(args, sc.name, f"route-{ckpt.method}-{args.world}")
    if record is not None:
        # lazy: scenarios.recording (rerun) costs 270 ms at startup
        from scenarios.recording.recorder import Recorder

        with Recorder.create(record, sc, model, method=ckpt.method, config=ckpt.config,
                             seed=-1, world=args.world, blueprint="route") as rec:
            poses = driven.poses if driven is not None else None
            rec.log_episode_trajectory(ckpt.episodes, np.asarray(route), poses=poses,
                                       kind="greedy-test")
            rec.log_values(ckpt.episodes, q_table(ckpt.state), greedy_actions(ckpt.state),
                           potential(ckpt.state))
            rec.log_route("greedy", route)
        print(f"recording: {record}")
    print(ascii_routes(model, route, optimum))
    shown = "G not reached" if length < 0 else f"{length} moves"
    verdict = "optimal" if length == len(optimum) - 1 else "not optimal"
    print(f"greedy route: {shown} ({verdict}); BFS optimum: {len(optimum) - 1} moves")
    if args.png:
        route_png(sc, model, route, Path(args.png),
                  f"{ckpt.config.name} greedy route ({args.world}) vs BFS optimum", trajectory)
        print(f"drawn to {args.png}")
    return 0

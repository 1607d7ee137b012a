"""``rnhql route``: a saved agent's greedy route from S against the BFS optimum.

The route is :func:`scenarios.api.route` (which checks every argument); this module prints
it, records it and draws it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from learning.compiled.readout import greedy_actions, potential, q_table
from scenarios.cli.args import compile_notice, in_flag_words, problem_arg
from scenarios.figures.routes import ascii_routes, route_png
from scenarios.sweep.outdir import check_output_file, record_path


def cmd_route(args: argparse.Namespace) -> int:
    from scenarios import api

    pb = problem_arg(args)  # the scenario loaded, --rewards/--fidelity parsed
    sc, model = pb.sc, pb.model
    if args.png:
        check_output_file(Path(args.png), "--png", ".png")
    if args.world == "physics":
        compile_notice(0, physics=True)
    with in_flag_words():
        r = api.route(args.agent, pb.scenario, world=args.world, fidelity=pb.fidelity,
                      rewards="scenario" if pb.rewards is None else pb.rewards,
                      start=pb.start, goal=pb.goal, with_optimum=False)
    print(f"{r.name} agent {args.agent} ({r.episodes} episodes) on {sc.name}")
    if r.grade is not None:
        g, first = r.grade, r.first_drive
        lo, hi = g.p_goal_ci95
        print(f"  driven in physics at {g.fidelity}: P(G) {g.p_goal:.2f} "
              f"[{lo:.2f}, {hi:.2f}] over {g.drives} drive(s); the drive shown "
              f"{'reached G' if first['reached'] else 'did not reach G'}, "
              f"{first['metres']:.1f} m, {first['contacts']} contacts, "
              f"{first['sim_time_s']:.1f} s sim time")
    record = record_path(args, sc.name, f"route-{r.method}-{args.world}")
    if record is not None:
        # lazy: scenarios.recording (rerun) costs 270 ms at startup
        from scenarios.recording.recorder import Recorder

        st = r.agent.state
        with Recorder.create(record, sc, model, method=r.method, config=r.agent.config,
                             seed=-1, world=args.world, blueprint="route") as rec:
            rec.log_episode_trajectory(r.episodes, np.asarray(r.cells), poses=r.poses,
                                       kind="greedy-test")
            rec.log_values(r.episodes, q_table(st), greedy_actions(st), potential(st))
            rec.log_route("greedy", list(r.cells))
        print(f"recording: {record}")
    print(ascii_routes(model, list(r.cells), list(r.optimal_cells)))
    print(f"greedy route: {'G not reached' if r.length < 0 else f'{r.length} moves'} "
          f"({'optimal' if r.optimal else 'not optimal'}); BFS optimum: "
          f"{len(r.optimal_cells) - 1} moves")
    if args.png:
        route_png(sc, model, list(r.cells), Path(args.png),
                  f"{r.name} greedy route ({args.world}) vs BFS optimum",
                  None if r.path is None else r.path[:, :2])
        print(f"drawn to {args.png}")
    return 0

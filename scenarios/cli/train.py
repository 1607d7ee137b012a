"""``rnhql train``: one method, one scenario, one seed; optional checkpoint and recording.

The flags go straight to :func:`scenarios.api.train`, which checks them (its refusals are
said in flag words, exit 2) and runs; this module prints what it is about to run and what
ran.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from scenarios.cli.args import (
    compile_notice,
    in_flag_words,
    parse_overrides,
    problem_arg,
    rewards_note,
    starts_note,
)
from scenarios.sweep.outdir import check_output_file, record_path
from sim.files import atomic_write_text


def cmd_train(args: argparse.Namespace) -> int:
    # lazy: scenarios.api (sweeps, values) costs 22 ms at startup
    from scenarios import api

    pb = problem_arg(args)  # the scenario loaded, --rewards/--s-starts/--fidelity parsed
    if args.json:  # a flag of the command's own (the library returns the record)
        check_output_file(Path(args.json), "--json")
    record = record_path(args, pb.sc.name, f"{args.method}-{args.world}-s{args.seed}")

    def announce(plan: api.TrainPlan) -> None:
        """Every argument checked, nothing trained yet: what is about to run."""
        world = plan.world if plan.fidelity is None else f"physics at fidelity {plan.fidelity}"
        print(f"{plan.method} on {plan.scenario.name} ({world}), seed {plan.seed}, "
              f"{plan.episodes} episodes, rewards {plan.scenario.rewards.label()}"
              f"{rewards_note(args)}{starts_note(plan.scenario)}")
        if plan.resumed_episodes is not None:
            print(f"resuming {args.resume}: {plan.resumed_episodes} of {plan.episodes} "
                  f"episodes done, training the other "
                  f"{max(plan.episodes - plan.resumed_episodes, 0)}")
        if args.init:
            print(f"warm start from {args.init}")
        compile_notice(1, physics=plan.world == "physics")

    with in_flag_words():  # the library checks every argument (and says so in flags)
        run = api.train(pb.scenario, args.method, world=args.world, fidelity=pb.fidelity,
                        episodes=args.episodes, seed=args.seed,
                        rewards="scenario" if pb.rewards is None else pb.rewards,
                        record=record, settings=dict(parse_overrides(args.set)),
                        s_starts=pb.s_starts, start=pb.start, goal=pb.goal, save=args.save,
                        resume=args.resume,
                        record_every=10 if args.record_every is None else args.record_every,
                        record_values_every=args.record_values_every, init=args.init,
                        pretrain=args.pretrain, announce=announce)
    if record is not None:
        print(f"  recording             {record}  (open: rnhql view {record})")
    print_run(dict(run.record), pb.model.optimal_route_length)
    print_pretrain(run)
    if args.save:
        print(f"  saved agent           {args.save}")
    if args.json:
        atomic_write_text(args.json, json.dumps(dict(run.record), indent=1))  # OSError: exit 1
    return 0


def print_pretrain(run) -> None:
    """What a warm-started run's first phase cost and what its policy was worth at the rung."""
    pre = run.pretrain
    if not pre:
        return
    cost = (f"{pre['episodes']} grid episodes ({pre['env_steps']:,} moves)"
            if pre["world"] == "grid" else
            f"{pre['episodes']} episodes at {pre['fidelity']} "
            f"({pre.get('robot_primitives', pre['env_steps']):,} primitives)")
    pol = pre["policy"]
    print(f"  first phase           {cost}; its policy here: P(G) {pol['p_goal']:.2f} over "
          f"{pol['rollouts']} drives")
    print(f"  robot time            {run.robot_primitives:,} primitives, "
          f"{run.robot_seconds:,.1f} s simulated")


def print_run(rec_like: dict, optimal: int) -> None:
    stable = rec_like.get("episodes_to_stable_optimal")
    first = rec_like["episodes_to_optimal"]
    length = rec_like["final_route_length"]
    print(f"  success rate          {rec_like['success_rate']:.3f}")
    print(f"  stable optimal after  {'never' if stable is None else f'{stable} episodes'} "
          f"(first optimal test: {'never' if first is None else f'episode {first}'})")
    pol = rec_like.get("final_policy")
    above = rec_like.get("world") == "physics" and (rec_like.get("fidelity") or "exact") != \
        "exact"
    if rec_like.get("world") == "physics":
        print(f"  physics fidelity      {rec_like.get('fidelity') or 'exact'}")
    what = "final greedy route" if not above else "final route (median)"
    print(f"  {what:<21} {'G not reached' if length < 0 else length} "
          f"(optimal {rec_like.get('optimal_route_length', optimal)})")
    if pol is not None and pol["rollouts"] > 1:
        lo, hi = pol["p_goal_ci95"]
        prims = pol["primitives_mean"]
        print(f"  final policy driven   {pol['rollouts']} times: P(G) {pol['p_goal']:.2f} "
              f"[{lo:.2f}, {hi:.2f}], {'—' if prims is None else f'{prims:.1f}'} primitives, "
              f"{pol['contacts_mean']:.1f} contacts per drive")
    print(f"  greedy moves on a shortest route  {rec_like['optimal_action_fraction']:.3f}")
    print(f"  env steps             {rec_like['env_steps']}")
    print(f"  wall time             {rec_like['wall_time_s']:.3f} s")

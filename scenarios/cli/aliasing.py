"""``rnhql aliasing``: the next-cell distribution of every (cell, action) at a fidelity."""

from __future__ import annotations

import argparse
from pathlib import Path

from scenarios.cli.args import compile_notice, positive, scenario_key, seed_value
from scenarios.cli.paths import check_output_file

MAX_REPEATS = 100_000  # drives per (cell, action)


def cmd_aliasing(args: argparse.Namespace) -> int:
    from scenarios.experiments.aliasing import run

    if args.artifact:
        from scenarios.artifacts import check_artifact_target

        check_artifact_target(args.artifact)
    name, start, goal = scenario_key(args)
    seed_value(args.seed, "--seed")
    positive(args.repeats, "--repeats", MAX_REPEATS)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        check_output_file(out / "aliasing.json", "--out")
    compile_notice(0, physics=True)
    run(argparse.Namespace(scenario=name, start=start, goal=goal, fidelity=args.fidelity or
                           "exact", repeats=args.repeats, seed=args.seed, rewards=args.rewards,
                           out=out, artifact=args.artifact))
    return 0

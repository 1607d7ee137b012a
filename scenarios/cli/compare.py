"""``rnhql compare``: methods x seeds (x worlds) on one scenario, locally or on Ray.
"""

from __future__ import annotations

import argparse
import os
import textwrap
from pathlib import Path

from learning.methods.registry import comparison_methods
from scenarios.cli.args import (
    MAX_EPISODES,
    MAX_SEEDS,
    check_world,
    compile_notice,
    in_flag_words,
    parse_list,
    parse_overrides,
    physics_budget,
    positive,
    problem_arg,
    rewards_note,
    seed_value,
    starts_note,
    unique,
)
from scenarios.runs.spec import make_config
from scenarios.sweep.brief import TERMINAL_COLUMNS
from scenarios.sweep.outdir import record_path
from sim.errors import InputError


def cmd_compare(args: argparse.Namespace) -> int:
    """Parse, check every flag (errors name the flag), run :func:`scenarios.api.compare`,
    print its summary."""
    # lazy: scenarios.api (sweeps, values) costs 22 ms at startup
    from scenarios import api

    pb = problem_arg(args)  # the scenario checked and loaded before any work
    name, sc = pb.scenario, pb.sc
    methods = (unique(parse_list(args.methods, "--methods"), "--methods") if args.methods
               else list(comparison_methods()))
    worlds = [check_world(w) for w in unique(parse_list(args.world, "--world"), "--world")]
    physics_budget(sc, worlds)
    overrides = parse_overrides(args.set)
    for m in methods:
        make_config(m, ())  # an unknown method fails here, naming --method
    api.settings_per_method(methods, overrides)  # a bad --set fails here, naming it
    n_seeds = positive(args.seeds, "--seeds", MAX_SEEDS)
    seed_base = seed_value(args.seed_base, "--seed-base", n_seeds)
    episodes = positive(args.episodes, "--episodes", MAX_EPISODES)
    _check_backend(args)
    record = record_path(args, name.rsplit("/", 1)[-1].removesuffix(".toml"), "compare")
    if record is not None:
        positive(100 if args.record_every is None else args.record_every, "--record-every")
        positive(args.record_values_every, "--record-values-every")
        positive(args.record_seeds, "--record-seeds")
    _say(f"{n_seeds * len(methods) * len(worlds)} runs on {sc.name}, rewards "
         f"{sc.rewards.label()}{rewards_note(args)}{starts_note(sc)}")
    compile_notice(len(methods), physics="physics" in worlds)
    out = Path(args.out)
    with in_flag_words():  # the library checks (--pretrain's only check is there)
        cmp = api.compare(pb.scenario, methods, worlds=worlds, fidelity=pb.fidelity,
                          seeds=n_seeds,
                          seed_base=seed_base, episodes=episodes,
                          rewards="scenario" if pb.rewards is None else pb.rewards,
                          settings=dict(overrides), jobs=args.jobs or os.cpu_count() or 1,
                          backend=args.backend, address=args.address, out=out,
                          resume=args.resume, record=record,
                          record_every=100 if args.record_every is None else args.record_every,
                          record_values_every=args.record_values_every,
                          record_seeds=args.record_seeds, s_starts=pb.s_starts, start=pb.start,
                          goal=pb.goal, progress=True, pretrain=args.pretrain)
    print(cmp.brief())
    _say(f"full tables and the pairwise verdicts: {out / 'summary.md'}; also results.json "
         f"and figures in {out}")
    if record is not None:
        _say(f"recording: {record}  (open: rnhql view {record})")
    return 0


def _say(text: str) -> None:
    """A line of the command's output, wrapped to the summary's 100 columns."""
    print("\n".join(textwrap.wrap(text, TERMINAL_COLUMNS, subsequent_indent="  ",
                                   break_on_hyphens=False, break_long_words=False)))


def _check_backend(args: argparse.Namespace) -> None:
    """``--jobs``, ``--backend`` and ``--address``, checked (errors name the flag)."""
    if args.jobs is not None:
        positive(args.jobs, "--jobs", 4096)
    if args.backend == "local":
        if args.address is not None:
            raise InputError("command line", "--address", "only applies with --backend ray",
                             "add --backend ray, or drop --address")
    elif args.backend != "ray":
        raise InputError("command line", "--backend", f"unknown backend {args.backend!r}",
                         "use local or ray")

"""``rnhql compare``: methods x seeds (x worlds) on one scenario, locally or on Ray.
"""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path

from scenarios.cli.args import (
    compile_notice,
    in_flag_words,
    parse_overrides,
    problem_arg,
    rewards_note,
    starts_note,
)
from scenarios.sweep.brief import TERMINAL_COLUMNS
from scenarios.sweep.outdir import record_path


def cmd_compare(args: argparse.Namespace) -> int:
    """Parse the flags, pass them to :func:`scenarios.api.compare` (the library checks every
    argument before any work; its refusals are said in flag words, exit 2), print its
    summary."""
    # lazy: scenarios.api (sweeps, values) costs 22 ms at startup
    from scenarios import api

    pb = problem_arg(args)  # the scenario loaded, --rewards/--s-starts/--fidelity parsed
    sc = pb.sc
    record = record_path(args, pb.scenario.rsplit("/", 1)[-1].removesuffix(".toml"), "compare")
    out = Path(args.out)

    def announce(n_runs: int, methods: list[str], worlds: list[str]) -> None:
        """Every argument checked, nothing run yet: what is about to run."""
        _say(f"{n_runs} runs on {sc.name}, rewards {sc.rewards.label()}{rewards_note(args)}"
             f"{starts_note(sc)}")
        compile_notice(len(methods), physics="physics" in worlds)

    methods = None if args.methods is None else [m.strip() for m in args.methods.split(",")]
    with in_flag_words(method="--methods"):
        cmp = api.compare(pb.scenario, methods, worlds=args.world, fidelity=pb.fidelity,
                          seeds=args.seeds, seed_base=args.seed_base, episodes=args.episodes,
                          rewards="scenario" if pb.rewards is None else pb.rewards,
                          settings=dict(parse_overrides(args.set)), jobs=args.jobs,
                          backend=args.backend, address=args.address, out=out,
                          resume=args.resume, record=record,
                          record_every=100 if args.record_every is None else args.record_every,
                          record_values_every=args.record_values_every,
                          record_seeds=args.record_seeds, s_starts=pb.s_starts, start=pb.start,
                          goal=pb.goal, progress=True, pretrain=args.pretrain,
                          announce=announce)
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

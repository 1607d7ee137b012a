"""``rnhql compare``: methods x seeds (x worlds) on one scenario, locally or on Ray.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from scenarios.cli.args import (
    check_world,
    parse_list,
    parse_overrides,
    positive,
    record_path,
    scenario_key,
)
from scenarios.runs.spec import load, make_config
from sim.errors import InputError


def cmd_compare(args: argparse.Namespace) -> int:
    from scenarios.experiments.compare import ALL_METHODS, make_specs, run_sweep

    name, start, goal = scenario_key(args)
    load(name, start, goal)  # validate the scenario before any work
    methods = parse_list(args.methods, "--methods") if args.methods else list(ALL_METHODS)
    worlds = [check_world(w) for w in parse_list(args.world, "--world")]
    overrides = parse_overrides(args.set)
    for m in methods:
        make_config(m, overrides)  # every method and override is valid before we start
    seeds = list(range(args.seed_base, args.seed_base + positive(args.seeds, "--seeds")))
    specs = make_specs(name, methods, seeds, positive(args.episodes, "--episodes"), worlds,
                       overrides, start, goal)
    execute, kwargs = _backend(args)
    from scenarios.runs.backends import Progress

    record = record_path(args, name.rsplit("/", 1)[-1].removesuffix(".toml"), "compare")
    if record is not None:
        from scenarios.experiments.compare import with_recording

        specs = with_recording(specs, record,
                               positive(100 if args.record_every is None else args.record_every,
                                         "--record-every"),
                               positive(args.record_values_every, "--record-values-every"),
                               positive(args.record_seeds, "--record-seeds"))
    run_sweep(specs, Path(args.out), execute, resume=args.resume,
              progress=Progress(len(specs)), **kwargs)
    if record is not None:
        from scenarios.experiments.compare import gather_parts

        gather_parts(specs, record)
        print(f"recording: {record}  (open: rnhql view {record})")
    print((Path(args.out) / "summary.md").read_text())
    print(f"wrote {args.out}/results.json, summary.md and figures")
    return 0


def _backend(args: argparse.Namespace):
    from scenarios.runs.backends import run_local, run_ray

    if args.backend == "local":
        return run_local, {"jobs": args.jobs or os.cpu_count() or 1}
    if args.backend == "ray":
        return run_ray, {"address": args.address, "num_cpus": args.jobs}
    raise InputError("command line", "--backend", f"unknown backend {args.backend!r}",
                     "use local or ray")

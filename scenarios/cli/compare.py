"""``rnhql compare``: methods x seeds (x worlds) on one scenario, locally or on Ray.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from scenarios.cli.args import (
    MAX_EPISODES,
    MAX_SEEDS,
    check_world,
    compile_notice,
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
from scenarios.cli.paths import record_path
from scenarios.runs.spec import ExperimentError, make_config
from sim.errors import InputError


def cmd_compare(args: argparse.Namespace) -> int:
    from learning.registry import comparison_methods
    from scenarios.experiments.compare import SweepRecording, make_specs, run_sweep

    pb = problem_arg(args)  # the scenario checked and loaded before any work
    name, sc = pb.scenario, pb.sc
    methods = (unique(parse_list(args.methods, "--methods"), "--methods") if args.methods
               else list(comparison_methods()))
    worlds = [check_world(w) for w in unique(parse_list(args.world, "--world"), "--world")]
    physics_budget(sc, worlds)
    overrides = parse_overrides(args.set)
    per_method = overrides_per_method(methods, overrides)
    n_seeds = positive(args.seeds, "--seeds", MAX_SEEDS)
    seed_base = seed_value(args.seed_base, "--seed-base", n_seeds)
    seeds = list(range(seed_base, seed_base + n_seeds))
    episodes = positive(args.episodes, "--episodes", MAX_EPISODES)
    specs = make_specs(name, methods, seeds, episodes, worlds, per_method, **pb.spec_fields())
    execute, kwargs = _backend(args)
    from scenarios.runs.backends import Progress

    record = record_path(args, name.rsplit("/", 1)[-1].removesuffix(".toml"), "compare")
    recording = None
    if record is not None:
        recording = SweepRecording(
            record, every=positive(100 if args.record_every is None else args.record_every,
                                   "--record-every"),
            values_every=positive(args.record_values_every, "--record-values-every"),
            detail_seeds=positive(args.record_seeds, "--record-seeds"))
    print(f"{len(specs)} runs on {sc.name}, rewards {sc.rewards.label()}{rewards_note(args)}"
          f"{starts_note(sc)}")
    compile_notice(len(methods))
    out = Path(args.out)
    run_sweep(specs, out, execute, resume=args.resume, recording=recording,
              progress=Progress(len(specs)), **kwargs)
    if record is not None:
        print(f"recording: {record}  (open: rnhql view {record})")
    print((out / "summary.md").read_text())
    print(f"wrote {out / 'results.json'}, summary.md and figures")
    return 0


def overrides_per_method(methods: list[str], overrides: tuple[tuple[str, float], ...]
                         ) -> dict[str, tuple[tuple[str, float], ...]]:
    """``--set`` applies to every method that has the field; an error only when none has it.

    Every method's config is built here once, so a bad value fails before any run starts.
    """
    import dataclasses

    from learning.registry import METHODS

    make_config(methods[0], ())  # an unknown method name fails here, with the list of names
    out: dict[str, tuple[tuple[str, float], ...]] = {}
    for m in methods:
        make_config(m, ())
        fields = {f.name for f in dataclasses.fields(METHODS[m])}
        out[m] = tuple((k, v) for k, v in overrides if k in fields)
        make_config(m, out[m])
    for k, _ in overrides:
        if not any(k in dict(o) for o in out.values()):
            raise ExperimentError("command line", f"--set {k}",
                                  f"none of the methods ({', '.join(methods)}) has a field "
                                  f"{k!r}", "use one of their fields: " + ", ".join(sorted(
                                      {f.name for m in methods
                                       for f in dataclasses.fields(METHODS[m])})))
    return out


def _backend(args: argparse.Namespace):
    from scenarios.runs.backends import run_local, run_ray

    if args.jobs is not None:
        positive(args.jobs, "--jobs", 4096)
    if args.backend == "local":
        if args.address is not None:
            raise InputError("command line", "--address", "only applies with --backend ray",
                             "add --backend ray, or drop --address")
        return run_local, {"jobs": args.jobs or os.cpu_count() or 1}
    if args.backend == "ray":
        return run_ray, {"address": args.address, "num_cpus": args.jobs}
    raise InputError("command line", "--backend", f"unknown backend {args.backend!r}",
                     "use local or ray")

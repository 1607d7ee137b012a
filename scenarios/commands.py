"""The work behind ``rnhql train``, ``route``, ``compare`` and ``bench``.

Each ``cmd_*`` takes the parsed arguments and returns an exit status; input
errors are raised as :class:`sim.errors.InputError` (or the learners'
``CheckpointError``) and turned into one line and exit 2 by :mod:`scenarios.cli`.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

import numpy as np

from scenarios.experiment import WORLDS, ExperimentError, load, make_config
from sim.errors import InputError


def parse_overrides(items: list[str] | None) -> tuple[tuple[str, float], ...]:
    out = []
    for item in items or []:
        key, sep, value = item.partition("=")
        try:
            if not sep:
                raise ValueError
            out.append((key.strip(), float(value)))
        except ValueError:
            raise ExperimentError("command line", f"--set {item}", "expected FIELD=NUMBER",
                                  "write e.g. --set alpha=0.2") from None
    return tuple(out)


def parse_list(text: str, flag: str, allowed: tuple[str, ...] | None = None) -> list[str]:
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise ExperimentError("command line", flag, "is empty", f"give e.g. {flag} a,b")
    if allowed is not None:
        bad = [t for t in items if t not in allowed]
        if bad:
            raise ExperimentError("command line", flag, f"unknown value {bad[0]!r}",
                                  f"use one of: {', '.join(allowed)}")
    return items


def check_world(world: str) -> str:
    if world not in WORLDS:
        raise ExperimentError("command line", "--world", f"unknown world {world!r}",
                              f"use one of: {', '.join(WORLDS)}")
    return world


def _positive(value: int, flag: str) -> int:
    if value < 1:
        raise ExperimentError("command line", flag, f"must be >= 1, got {value}",
                              f"pass e.g. {flag} 10")
    return value


def _scenario_key(args: argparse.Namespace) -> tuple[str, tuple | None, tuple | None]:
    from scenarios.cli import parse_cell

    start = parse_cell(args.start, "--start") if args.start else None
    goal = parse_cell(args.goal, "--goal") if args.goal else None
    return args.scenario, start, goal


def print_run(rec_like: dict, optimal: int) -> None:
    eto = rec_like["episodes_to_optimal"]
    length = rec_like["final_route_length"]
    print(f"  success rate          {rec_like['success_rate']:.3f}")
    print(f"  episodes to optimal   {'never' if eto is None else eto}")
    print(f"  final greedy route    {'G not reached' if length < 0 else length} "
          f"(optimal {optimal})")
    print(f"  greedy moves on a shortest route  {rec_like['optimal_action_fraction']:.3f}")
    print(f"  env steps             {rec_like['env_steps']}")
    print(f"  wall time             {rec_like['wall_time_s']:.3f} s")


def cmd_train(args: argparse.Namespace) -> int:
    from learning.checkpoint import Checkpoint, load_checkpoint, save_checkpoint
    from learning.train import train_tabular
    from scenarios.experiment import RunSpec, run_record

    name, start, goal = _scenario_key(args)
    sc, model = load(name, start, goal)
    check_world(args.world)
    _positive(args.episodes, "--episodes")
    cfg = make_config(args.method, parse_overrides(args.set))
    spec = RunSpec(name, args.method, args.seed, args.episodes, args.world, start=start,
                   goal=goal)
    record = _record_path(args, sc.name, f"{args.method}-{args.world}-s{args.seed}")
    rng = np.random.default_rng(args.seed)
    if args.save:
        _check_writable(Path(args.save), "--save")
    resume = None
    if args.resume and args.world == "grid":
        resume = load_checkpoint(args.resume, args.method, model.n_states)
    print(f"{cfg.name} on {sc.name} ({args.world}), seed {args.seed}, {args.episodes} episodes")
    recorder = plan = observer = None
    if record is not None:
        from scenarios.recorded_runs import GridRecorder, RecordPlan
        from scenarios.recording import Recorder

        plan = RecordPlan(args.episodes,
                          every=_positive(10 if args.record_every is None else args.record_every,
                                            "--record-every"),
                          values_every=_positive(args.record_values_every,
                                                 "--record-values-every"))
        recorder = Recorder.create(record, sc, model, method=args.method, config=cfg,
                                   seed=args.seed, world=args.world)
        observer = GridRecorder(recorder, plan)
    try:
        if args.world == "grid":
            result = train_tabular(cfg, model, args.episodes, rng, resume=resume,
                                   observer=observer)
            if args.save:
                save_checkpoint(args.save, Checkpoint.of_result(result, rng))
        else:
            if args.resume:
                raise ExperimentError("command line", "--resume", "is only supported for grid "
                                      "runs", "drop --resume or use --world grid")
            from scenarios.physics_runs import train_physics

            result = train_physics(cfg, sc, model, args.episodes, rng, recorder=recorder,
                                   plan=plan)
            if args.save:
                save_checkpoint(args.save, Checkpoint.of_agent(result.agent))
        if recorder is not None:
            recorder.log_route("greedy final", result.final_route)
    finally:
        if recorder is not None:
            recorder.close()  # also on Ctrl-C: the recording keeps what was logged
    if record is not None:
        print(f"  recording             {record}  (open: rnhql view {record})")
    rec = run_record(spec, cfg, result, model)
    print_run(rec, model.optimal_route_length)
    if args.save:
        print(f"  saved agent           {args.save}")
    if args.json:
        from scenarios.results import atomic_write_text

        atomic_write_text(args.json, json.dumps(rec, indent=1))
    return 0


def _record_path(args: argparse.Namespace, scenario: str, rest: str) -> str | None:
    """``--record`` given: its path, or the default under recordings/; else None."""
    if args.record is None:
        return None
    path = Path(args.record or f"recordings/{scenario}-{rest}.rrd")
    if path.suffix != ".rrd":
        raise ExperimentError("command line", "--record", f"{path} does not end in .rrd",
                              "name the recording e.g. run.rrd")
    path.parent.mkdir(parents=True, exist_ok=True)
    _check_writable(path, "--record")
    return str(path)


def _check_writable(path: Path, flag: str) -> None:
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir() or not os.access(parent, os.W_OK):
        raise ExperimentError("command line", flag, f"cannot write to {parent}/",
                              "create the directory or pick another path")


def cmd_route(args: argparse.Namespace) -> int:
    from learning.checkpoint import load_checkpoint
    from learning.train import greedy_test
    from scenarios.route_view import ascii_routes, route_png
    from sim.planning import bfs_route

    name, start, goal = _scenario_key(args)
    sc, model = load(name, start, goal)
    check_world(args.world)
    ckpt = load_checkpoint(args.agent, None, model.n_states)
    optimum = bfs_route(model.next_state, model.distance_to_goal, model.start)
    length, route = greedy_test(ckpt.state, model)
    trajectory = driven = None
    print(f"{ckpt.config.name} agent {args.agent} ({ckpt.episodes} episodes) on {sc.name}")
    if args.world == "physics":
        from learning.agent import StepAgent
        from learning.geometry import geometry_of
        from scenarios.physics_runs import drive_greedy

        agent = StepAgent(ckpt.config, geometry_of(model), np.random.default_rng(0), ckpt.state)
        driven = drive_greedy(agent, sc)
        route, trajectory = driven.states, driven.trajectory
        length = len(route) - 1 if driven.reached else -1
        print(f"  driven in physics: {'reached G' if driven.reached else 'did not reach G'}, "
              f"{driven.metres:.1f} m, {driven.contacts} contacts, {driven.sim_time_s:.1f} s "
              "sim time")
    record = _record_path(args, sc.name, f"route-{ckpt.method}-{args.world}")
    if record is not None:
        from learning.readout import greedy_actions, potential, q_table
        from scenarios.recording import Recorder

        with Recorder.create(record, sc, model, method=ckpt.method, config=ckpt.config,
                             seed=-1, world=args.world) as rec:
            poses = driven.poses if args.world == "physics" else None
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


def cmd_compare(args: argparse.Namespace) -> int:
    from scenarios.compare import ALL_METHODS, make_specs, run_sweep

    name, start, goal = _scenario_key(args)
    load(name, start, goal)  # validate the scenario before any work
    methods = parse_list(args.methods, "--methods") if args.methods else list(ALL_METHODS)
    worlds = [check_world(w) for w in parse_list(args.world, "--world")]
    overrides = parse_overrides(args.set)
    for m in methods:
        make_config(m, overrides)  # every method and override is valid before we start
    seeds = list(range(args.seed_base, args.seed_base + _positive(args.seeds, "--seeds")))
    specs = make_specs(name, methods, seeds, _positive(args.episodes, "--episodes"), worlds,
                       overrides, start, goal)
    execute, kwargs = _backend(args)
    from scenarios.backends import Progress

    record = _record_path(args, name.rsplit("/", 1)[-1].removesuffix(".toml"), "compare")
    if record is not None:
        from scenarios.compare import with_recording

        specs = with_recording(specs, record,
                               _positive(100 if args.record_every is None else args.record_every,
                                         "--record-every"),
                               _positive(args.record_values_every, "--record-values-every"),
                               _positive(args.record_seeds, "--record-seeds"))
    run_sweep(specs, Path(args.out), execute, resume=args.resume,
              progress=Progress(len(specs)), **kwargs)
    if record is not None:
        from scenarios.compare import gather_parts

        gather_parts(specs, record)
        print(f"recording: {record}  (open: rnhql view {record})")
    print((Path(args.out) / "summary.md").read_text())
    print(f"wrote {args.out}/results.json, summary.md and figures")
    return 0


def _backend(args: argparse.Namespace):
    from scenarios.backends import run_local, run_ray

    if args.backend == "local":
        return run_local, {"jobs": args.jobs or os.cpu_count() or 1}
    if args.backend == "ray":
        return run_ray, {"address": args.address, "num_cpus": args.jobs}
    raise InputError("command line", "--backend", f"unknown backend {args.backend!r}",
                     "use local or ray")


def cmd_bench(args: argparse.Namespace) -> int:
    from scenarios import bench_grid

    figures: dict = {"foundation": bench_grid.run_bench()}
    try:
        from scenarios import bench

        figures["learning"] = bench.run_bench()
    except ImportError:
        pass
    if args.physics:
        from scenarios import bench_physics

        figures["physics"] = bench_physics.run_bench()
    if args.json:
        print(json.dumps(figures, indent=1))
    else:
        for section, values in figures.items():
            print(f"[{section}]")
            for k, v in values.items():
                print(f"  {k:<44} {v:,.4g}" if isinstance(v, float) else f"  {k:<44} {v}")
    return 0


def cmd_view(args: argparse.Namespace) -> int:
    """Open a recording: the native viewer, or the web viewer served on loopback."""
    import subprocess

    from scenarios.recording import rerun_cli

    path = Path(args.file)
    if not path.is_file():
        raise InputError(str(path), "FILE", "does not exist", "pass a .rrd written by --record")
    cmd = [rerun_cli(), str(path)]
    if args.web:
        cmd += ["--serve-web", "--bind", "127.0.0.1", "--web-viewer-port", str(args.port)]
        print(f"serving {path} at http://127.0.0.1:{args.port} (Ctrl-C to stop)")
    try:
        return subprocess.call(cmd)
    except KeyboardInterrupt:
        return 0

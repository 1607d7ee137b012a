"""``rnhql train``: one method, one scenario, one seed; optional checkpoint and recording.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from learning.streams import streams
from scenarios.cli.args import (
    MAX_EPISODES,
    check_world,
    parse_overrides,
    physics_budget,
    positive,
    print_run,
    problem_arg,
    rewards_note,
    seed_value,
    starts_note,
)
from scenarios.cli.paths import check_output_file, record_path
from scenarios.runs.spec import ExperimentError, make_config
from sim.files import atomic_write_bytes, atomic_write_text


def cmd_train(args: argparse.Namespace) -> int:
    from learning.checkpoint import Checkpoint, checkpoint_bytes, load_checkpoint
    from learning.geometry import geometry_of
    from learning.train import train_tabular
    from scenarios.runs.spec import (
        RunOutcome,
        RunSpec,
        layout_digest,
        run_record,
        scenario_digest,
    )

    pb = problem_arg(args)
    sc, model = pb.sc, pb.model
    check_world(args.world)
    physics_budget(sc, [args.world])
    positive(args.episodes, "--episodes", MAX_EPISODES)
    seed_value(args.seed, "--seed")
    if args.json:
        check_output_file(Path(args.json), "--json")
    if args.save:  # a folder at --save fails now, not after training (the agent lost)
        check_output_file(Path(args.save), "--save")
    if args.resume and args.world != "grid":
        raise ExperimentError("command line", "--resume", "is only supported for grid runs",
                              "drop --resume or use --world grid")
    cfg = make_config(args.method, parse_overrides(args.set))
    spec = RunSpec(pb.scenario, args.method, args.seed, args.episodes, args.world,
                   **pb.spec_fields())
    record = record_path(args, sc.name, f"{args.method}-{args.world}-s{args.seed}")
    problem = {"scenario": scenario_digest(*pb.key), "rewards": sc.rewards.label(),
               "layout": layout_digest(pb.scenario, pb.start, pb.goal)}
    rs = streams(args.seed)  # the same streams as a run of `rnhql compare`
    rng = rs.learner
    resume = None
    if args.resume and args.world == "grid":
        resume = load_checkpoint(args.resume, args.method, model.n_states, geometry_of(model))
        resume.check_problem(problem)
    world = (args.world if args.world == "grid" else
             f"physics at fidelity {spec.fidelity_spec.label}")
    print(f"{cfg.name} on {sc.name} ({world}), seed {args.seed}, {args.episodes} episodes, "
          f"rewards {sc.rewards.label()}{rewards_note(args)}{starts_note(sc)}")
    recorder = plan = observer = None
    if record is not None:
        from scenarios.recording.hooks import GridRecorder, RecordPlan
        from scenarios.recording.recorder import Recorder

        plan = RecordPlan(args.episodes,
                          every=positive(10 if args.record_every is None else args.record_every,
                                            "--record-every"),
                          values_every=positive(args.record_values_every,
                                                 "--record-values-every"))
        recorder = Recorder.create(record, sc, model, method=args.method, config=cfg,
                                   seed=args.seed, world=args.world,
                                   fidelity=(spec.fidelity_spec.label
                                             if args.world == "physics" else None))
        observer = GridRecorder(recorder, plan)
    try:
        if args.world == "grid":
            result = train_tabular(cfg, model, args.episodes, rng, resume=resume,
                                   observer=observer, start_rng=rs.starts)
            if args.save:
                ck = Checkpoint.of_result(result, rng, rs.starts)
                ck.problem = problem
                atomic_write_bytes(args.save, checkpoint_bytes(ck))
        else:
            from scenarios.runs.physics import train_physics

            result = train_physics(cfg, sc, model, args.episodes, rng, recorder=recorder,
                                   plan=plan, start_rng=rs.starts,
                                   fidelity=spec.fidelity_spec, noise_rng=rs.physics,
                                   grading_seed=args.seed)
            if args.save:
                ck = Checkpoint.of_agent(result.agent)
                ck.problem = problem
                atomic_write_bytes(args.save, checkpoint_bytes(ck))
        if recorder is not None:
            if args.world == "physics":
                from scenarios.runs.physics import log_final

                log_final(recorder, result)
            else:
                recorder.log_route("final route", result.final_route)
    finally:
        if recorder is not None:
            recorder.close()  # also on Ctrl-C: the recording keeps what was logged
    if record is not None:
        print(f"  recording             {record}  (open: rnhql view {record})")
    from learning.train import epsilon_route_lengths

    # the paper's epsilon-greedy test on the evaluation stream, as `rnhql compare` runs it
    if args.world == "grid":
        eps_routes = epsilon_route_lengths(result.state, model, cfg.eps, rs.evaluation)
    else:
        eps_routes = result.grader.epsilon_routes(result.agent.state, cfg.eps, rs.evaluation)
    rec = run_record(spec, cfg, RunOutcome.of(result, eps_routes))
    print_run(rec, model.optimal_route_length)
    if args.save:
        print(f"  saved agent           {args.save}")
    if args.json:
        atomic_write_text(args.json, json.dumps(rec, indent=1))  # OSError: one line, exit 1
    return 0

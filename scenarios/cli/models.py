"""The physics world at a fidelity as a stochastic model: ``rnhql optimum`` and ``rnhql aliasing``.

``rnhql optimum``: V*, the optimum of the physics world at a fidelity (the yardstick).

"Optimal at F" means matching V* at F (``/work/shared/DESIGN.md``, Fidelity): the
expected primitives from S under the best policy in the stochastic model of the physics
world at that fidelity, built by driving (:mod:`sim.physics.models.build`) and solved
by value iteration (:mod:`sim.physics.models.solve`). The command prints it next to
the exact optimum and the continuous one, with what the model cost to build; with
``--rollouts N`` it also drives the optimal policy N times as a check.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from scenarios.artifacts import check_artifact_target, write_artifact
from scenarios.cli.args import (
    compile_notice,
    positive,
    scenario_from_args,
    scenario_key,
    seed_value,
)
from scenarios.sweep.outdir import check_output_file
from sim.grid.actions import ACTION_NAMES
from sim.physics.fidelity import parse_fidelity
from sim.physics.models.build import cache_dir, digest, stochastic_model
from sim.physics.models.optimum import continuous_optimum_m
from sim.physics.models.solve import solve
from sim.physics.models.stochastic import (
    ARRIVED,
    FACING,
    MAX_SAMPLES,
    REFINE,
    RESTING,
    Sampling,
    is_resting,
)
from sim.physics.models.stochastic_rollouts import drive_model_policy
from sim.physics.models.transition import physics_model
from sim.physics.static import PhysicsConfig

MAX_ROLLOUTS = 100_000
MAX_REPEATS = 100_000  # aliasing: drives per (cell, action)


def _states_line(model) -> str:
    counts = model.context_counts()
    facing = counts[FACING:FACING + len(ACTION_NAMES)]
    resting = counts[RESTING:RESTING + len(ACTION_NAMES)]
    resting_families = len({(int(c), int(x)) for c, x in
                            zip(model.state_cell, model.state_context, strict=True)
                            if RESTING <= x < FACING})
    parts = []
    if counts[ARRIVED]:
        parts.append(f"{counts[ARRIVED]:,} arrived")
    if facing.sum():
        parts.append(f"{facing.sum():,} arrived facing ("
                     + ", ".join(f"{n} {k:,}" for n, k in zip(ACTION_NAMES, facing, strict=True))
                     + ")")
    if resting.sum():
        parts.append(f"{resting.sum():,} resting: rest poses in {resting_families:,} "
                     "(cell, bumped action) pairs")
    return f"{model.n_states:,} states: " + "; ".join(parts)


def cmd_optimum(args: argparse.Namespace) -> int:
    if getattr(args, "artifact", None):
        check_artifact_target(args.artifact)  # before the work: a name, in a checkout
    fid = parse_fidelity(args.fidelity)
    samples = (None if args.samples is None
               else positive(args.samples, "--samples", MAX_SAMPLES // REFINE))
    seed = seed_value(args.seed, "--seed")
    rollouts = args.rollouts
    if rollouts:
        positive(rollouts, "--rollouts", MAX_ROLLOUTS)
    sc = scenario_from_args(args)
    compile_notice(0, physics=True)
    sampling = Sampling.default(fid, samples, seed)
    path = cache_dir() / f"{digest(sc, PhysicsConfig(), fid, sampling)}.npz"
    cached = path.exists()
    t0 = time.perf_counter()
    model = stochastic_model(sc, fid, sampling)
    wall = time.perf_counter() - t0
    budget = sc.steps_per_episode
    opt = solve(model, budget)
    exact = physics_model(sc).optimal_route_length
    continuous = continuous_optimum_m(sc)

    sp = model.sampling
    print(f"{sc.name} at fidelity {fid.label}: the optimum in the physics world (V*)")
    print(f"  model       {_states_line(model)}")
    how = (f"{sp.samples} drives per (state, action), {sp.refined} where they disagreed"
           if sp.refined > sp.samples else f"{sp.samples} drive(s) per (state, action)")
    if is_resting(model.state_context).any():
        how += f"; {sp.particles} rest poses x {sp.particle_samples} drives"
    built = f"{model.primitives:,} primitives driven in {model.build_s:.1f} s"
    if cached and wall < model.build_s:
        built = f"loaded from the cache in {wall:.1f} s (built from {built})"
    print(f"  built       {built}; {how}; seed {sp.seed}")
    start = opt.start
    if math.isinf(start.expected_primitives):
        print("  V*(S)       inf: no policy reaches G with probability 1 in the model")
    else:
        print(f"  V*(S)       {start.expected_primitives:.2f} expected primitives "
              f"(value iteration, {opt.sweeps} sweeps)")
    print(f"  P(G)        {start.p_goal_within_budget:.4f} within the episode's {budget} "
          "primitives, under the optimal policy")
    print(f"  exact       {exact if exact >= 0 else 'G not reached'} primitives "
          "(the physics world at exact)")
    if continuous is not None:
        print(f"  continuous  {continuous:.1f} m (Theta* path of the disc: an upper bound on "
              "the shortest)")
    if rollouts:
        r = drive_model_policy(sc, model, opt.policy, rollouts, seed=seed + 1)
        lo, hi = r.p_goal_interval
        print(f"  driven      {rollouts} rollouts of the optimal policy: P(G) {r.p_goal:.4f} "
              f"(95 % interval {lo:.3f}-{hi:.3f}), mean {r.mean_primitives:.2f} primitives "
              f"(median {r.median_primitives:g}), {r.mean_contacts:.2f} contacts per rollout")
    if getattr(args, "artifact", None):
        driven = None if not rollouts else {
            "rollouts": rollouts, "p_goal": r.p_goal, "p_goal_ci95": list(r.p_goal_interval),
            "primitives_mean": r.mean_primitives, "contacts_mean": r.mean_contacts}
        cmd = (f"rnhql optimum {args.scenario} --fidelity {fid.label} --seed {seed}"
               + ("" if samples is None else f" --samples {samples}")
               + (f" --rollouts {rollouts}" if rollouts else "")
               + f" --artifact {args.artifact}")
        write_artifact(f"optimum.{args.artifact}", cmd, ["physics-exact", "physics-noisy"], {
            "scenario": sc.name, "fidelity": fid.label, "budget": budget,
            "v_star": None if math.isinf(start.expected_primitives)
            else start.expected_primitives,
            "p_goal": start.p_goal_within_budget, "exact": exact, "continuous_m": continuous,
            "states": int(model.n_states), "drives": int(model.primitives),
            "build_s": float(model.build_s), "driven": driven}, study=__file__)
    return 0


def cmd_aliasing(args: argparse.Namespace) -> int:
    """``rnhql aliasing``: the next-cell distribution of every (cell, action) at a fidelity."""
    # lazy: the aliasing study (matplotlib) costs 290 ms at startup
    from scenarios.studies.ladder.aliasing import run

    if args.artifact:
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

"""The physics world at a fidelity as a stochastic model: ``rnhql optimum`` and ``rnhql aliasing``;
and checked by an independent simulator: ``rnhql crosscheck``.

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
import json
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
from sim.errors import InputError
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
MAX_PAIRS = 10_000  # crosscheck: (cell, action) pairs (IR-SIM drives about 20 a second)
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


def cmd_crosscheck(args: argparse.Namespace) -> int:
    """``rnhql crosscheck``: the same primitives, and policies, in IR-SIM (see
    :mod:`sim.physics.crosscheck.agreement`): how far the two simulators agree."""
    from learning.compiled.readout import greedy_actions
    from learning.drivers.checkpoint import load_checkpoint
    from learning.geometry import geometry_of
    from scenarios.runs.spec import layout_digest, load
    from sim.files import atomic_write_text
    from sim.physics.crosscheck import agreement
    from sim.physics.crosscheck.agreement import (
        CrosscheckOptions,
        crosscheck,
        grid_optimal_policy,
    )
    from sim.physics.crosscheck.irsim_world import _irsim, check_rung

    if args.artifact:
        check_artifact_target(args.artifact)
    if args.json:
        check_output_file(Path(args.json), "--json", ".json")
    fid = parse_fidelity(args.fidelity)
    check_rung(fid)  # before any work: a rung IR-SIM cannot model is refused
    _irsim()  # ... and a missing IR-SIM
    options = CrosscheckOptions(pairs=positive(args.pairs, "--pairs", MAX_PAIRS),
                                repeats=positive(args.repeats, "--repeats", MAX_REPEATS),
                                policy_drives=positive(args.drives, "--drives", MAX_ROLLOUTS),
                                seed=seed_value(args.seed, "--seed"))
    name, start, goal = scenario_key(args)
    sc, model = load(name, start, goal, getattr(args, "rewards", None))
    policies = {}
    for word in args.policy or []:
        if word != "optimal":
            raise InputError("command line", "--policy", f"{word!r} is not a policy name",
                             "use --policy optimal (the grid's), or --agent FILE")
        policies["grid optimal"] = grid_optimal_policy(model)
    for path in args.agent or []:
        ckpt = load_checkpoint(path, None, model.n_states, geometry_of(model))
        ckpt.check_problem({"layout": layout_digest(name, start, goal)})
        policies[f"{ckpt.method} ({Path(path).name})"] = greedy_actions(ckpt.state)
    compile_notice(0, physics=True)
    print(f"{sc.name} at {fid.label}: the same primitives in this physics and in IR-SIM")
    result = crosscheck(sc, model, fid, options, policies)
    _print_crosscheck(result)
    if args.json:
        atomic_write_text(Path(args.json), json.dumps(result, indent=1) + "\n")
        print(f"wrote {args.json}")
    if args.artifact:
        words = ["rnhql crosscheck", name, "--fidelity", fid.name if fid.label == fid.name
                 else args.fidelity, "--pairs", str(options.pairs), "--repeats",
                 str(options.repeats), "--drives", str(options.policy_drives), "--seed",
                 str(options.seed)]
        words += [w for p in args.policy or [] for w in ("--policy", p)]
        words += [w for p in args.agent or [] for w in ("--agent", p)]
        words += ["--artifact", args.artifact]
        path = write_artifact(f"crosscheck.{args.artifact}", " ".join(words),
                              ["physics-exact", "physics-noisy"], result,
                              study=agreement.__file__)  # its edits make the table stale
        print(f"wrote {path}")
    return 0


def _print_crosscheck(r: dict) -> None:
    def f(x: float | None, digits: int = 3) -> str:
        return "—" if x is None else f"{x:.{digits}f}"

    sec = r["seconds"]
    print(f"  {r['pairs']} (cell, action) pairs x {r['repeats']} drive(s): "
          f"{sec['rnhql']:.1f} s here, {sec['irsim']:.1f} s in IR-SIM")
    print("  stratum             pairs  bump-or-not agrees  |P(bump) gap|  class agrees  "
          "total variation")
    for name, t in r["strata"].items():
        print(f"  {name:<18} {t['pairs']:>6}  {f(t['bump_agree']):>18}  "
              f"{f(t['bump_gap']):>13}  {f(t['class_agree']):>12}  {f(t['tv']):>15}")
    for name, p in r["policies"].items():
        print(f"  policy {name}: P(G) {p['p_goal_rnhql']:.2f} here, {p['p_goal_irsim']:.2f} "
              f"in IR-SIM over {p['drives']} drive(s); primitives to G "
              f"{f(p['primitives_rnhql'], 1)} here, {f(p['primitives_irsim'], 1)} in IR-SIM")

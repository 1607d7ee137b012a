"""``rnhql optimum``, ``rnhql aliasing`` and ``rnhql crosscheck``: the physics world as a
model, printed. Each is a call of the library (:mod:`scenarios.api_models`, re-exported by
:mod:`scenarios.api`), which checks every argument; this module prints what it returns and
writes the artifact, whose command line is derived from the declared flags.

``rnhql optimum``: V*, the optimum of the physics world at a fidelity (the yardstick).
"Optimal at F" means matching V* at F (``/work/shared/DESIGN.md``, Fidelity): the
expected primitives from S under the best policy in the stochastic model of the physics
world at that fidelity, built by driving and solved by value iteration. The command prints
it next to the exact optimum and the continuous one, with what the model cost to build;
with ``--rollouts N`` it also drives the optimal policy N times as a check.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from scenarios.artifacts import check_artifact_target, write_artifact
from scenarios.cli.args import compile_notice, in_flag_words, scenario_key
from scenarios.script_args import command_line
from scenarios.sweep.outdir import check_output_file
from sim.grid.actions import ACTION_NAMES


def _artifact_command(args: argparse.Namespace) -> str:
    return command_line(f"rnhql {args.command}", args._parser, args)


def _compiling(scenario: str, fidelity: str) -> None:
    """Every argument checked: say so if the physics kernels compile first."""
    compile_notice(0, physics=True)


def _model_line(b) -> str:
    parts = []
    if b.arrived:
        parts.append(f"{b.arrived:,} arrived")
    if sum(b.facing):
        parts.append(f"{sum(b.facing):,} arrived facing ("
                     + ", ".join(f"{n} {k:,}" for n, k in zip(ACTION_NAMES, b.facing,
                                                               strict=True)) + ")")
    if b.resting:
        parts.append(f"{b.resting:,} resting: rest poses in {b.resting_pairs:,} "
                     "(cell, bumped action) pairs")
    return f"{b.states:,} states: " + "; ".join(parts)


def cmd_optimum(args: argparse.Namespace) -> int:
    from scenarios import api

    if args.artifact:
        check_artifact_target(args.artifact)  # before the work: a name, in a checkout
    name, start, goal = scenario_key(args)
    with in_flag_words():
        opt = api.optimum(name, fidelity=args.fidelity, rewards=args.rewards,
                          start=start, goal=goal, samples=args.samples, seed=args.seed,
                          rollouts=args.rollouts, announce=_compiling)
    print(f"{opt.scenario} at fidelity {opt.fidelity}: the optimum in the physics world (V*)")
    b = opt.model
    if b is None:
        print(f"  V*(S)       undefined: fidelity {opt.fidelity} has hidden state (open loop or "
              "localisation) the model's states do not capture; grade by driving "
              "(rnhql compare ... --fidelity F) and compare with the best method")
    else:
        print(f"  model       {_model_line(b)}")
        how = (f"{b.samples} drives per (state, action), {b.refined} where they disagreed"
               if b.refined > b.samples else f"{b.samples} drive(s) per (state, action)")
        if b.particles:
            how += f"; {b.particles} rest poses x {b.particle_samples} drives"
        built = f"{b.primitives:,} primitives driven in {b.build_s:.1f} s"
        if b.loaded_s is not None:
            built = f"loaded from the cache in {b.loaded_s:.1f} s (built from {built})"
        print(f"  built       {built}; {how}; seed {b.seed}")
        if math.isinf(opt.expected_primitives):
            print("  V*(S)       inf: no policy reaches G with probability 1 in the model")
        else:
            print(f"  V*(S)       {opt.expected_primitives:.2f} expected primitives "
                  f"(value iteration, {b.sweeps} sweeps)")
        print(f"  P(G)        {opt.p_goal_within_budget:.4f} within the episode's {opt.budget} "
              "primitives, under the optimal policy")
    exact = opt.physics_route_length
    print(f"  exact       {exact if exact >= 0 else 'G not reached'} primitives "
          "(the physics world at exact)")
    if opt.continuous_route_m is not None:
        print(f"  continuous  {opt.continuous_route_m:.1f} m (Theta* path of the disc: an "
              "upper bound on the shortest)")
    r = opt.driven
    if r is not None:
        lo, hi = r.p_goal_interval
        print(f"  driven      {r.n} rollouts of the optimal policy: P(G) {r.p_goal:.4f} "
              f"(95 % interval {lo:.3f}-{hi:.3f}), mean {r.mean_primitives:.2f} primitives "
              f"(median {r.median_primitives:g}), {r.mean_contacts:.2f} contacts per rollout")
    if args.artifact and b is not None:
        driven = None if r is None else {
            "rollouts": r.n, "p_goal": r.p_goal, "p_goal_ci95": list(r.p_goal_interval),
            "primitives_mean": r.mean_primitives, "contacts_mean": r.mean_contacts}
        write_artifact(f"optimum.{args.artifact}", _artifact_command(args),
                       ["physics-exact", "physics-noisy"], {
                           "scenario": opt.scenario, "fidelity": opt.fidelity, "budget": opt.budget,
                           "v_star": None if math.isinf(opt.expected_primitives)
                           else opt.expected_primitives,
                           "p_goal": opt.p_goal_within_budget, "exact": exact,
                           "continuous_m": opt.continuous_route_m, "states": b.states,
                           "drives": b.primitives, "build_s": b.build_s, "driven": driven},
                       study=__file__)
    return 0


def cmd_aliasing(args: argparse.Namespace) -> int:
    """``rnhql aliasing``: the next-cell distribution of every (cell, action) at a fidelity."""
    # lazy: the aliasing study (matplotlib) costs 290 ms at startup
    from scenarios import api
    from scenarios.studies.ladder.aliasing import report

    if args.artifact:
        check_artifact_target(args.artifact)
    name, start, goal = scenario_key(args)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        check_output_file(out / "aliasing.json", "--out")
    with in_flag_words():
        result = api.aliasing(name, fidelity=args.fidelity, repeats=args.repeats,
                              seed=args.seed, rewards=args.rewards, start=start, goal=goal,
                              announce=_compiling)
    report(result, out, args.artifact, _artifact_command(args))
    return 0


def cmd_crosscheck(args: argparse.Namespace) -> int:
    """``rnhql crosscheck``: the same primitives, and policies, in IR-SIM (see
    :mod:`sim.physics.crosscheck.agreement`): how far the two simulators agree."""
    from scenarios import api
    from sim.files import atomic_write_text
    from sim.physics.crosscheck import agreement

    if args.artifact:
        check_artifact_target(args.artifact)
    if args.json:
        check_output_file(Path(args.json), "--json", ".json")
    name, start, goal = scenario_key(args)

    def announce(scenario: str, fidelity: str) -> None:
        _compiling(scenario, fidelity)
        print(f"{scenario} at {fidelity}: the same primitives in this physics and in IR-SIM")

    with in_flag_words(policies="--policy", agents="--agent"):
        result = api.crosscheck(name, fidelity=args.fidelity, pairs=args.pairs,
                                repeats=args.repeats, drives=args.drives, seed=args.seed,
                                policies={"grid optimal": "optimal"} if args.policy else None,
                                agents=args.agent or (), rewards=args.rewards, start=start,
                                goal=goal, announce=announce)
    _print_crosscheck(result)
    if args.json:
        atomic_write_text(Path(args.json), json.dumps(result.as_dict(), indent=1) + "\n")
        print(f"wrote {args.json}")
    if args.artifact:
        path = write_artifact(f"crosscheck.{args.artifact}", _artifact_command(args),
                              ["physics-exact", "physics-noisy"], result.as_dict(),
                              study=agreement.__file__)  # its edits make the table stale
        print(f"wrote {path}")
    return 0


def _print_crosscheck(r) -> None:
    def f(x: float | None, digits: int = 3) -> str:
        return "—" if x is None else f"{x:.{digits}f}"

    print(f"  {r.pairs} (cell, action) pairs x {r.repeats} drive(s): "
          f"{r.seconds_rnhql:.1f} s here, {r.seconds_irsim:.1f} s in IR-SIM")
    print("  stratum             pairs  bump-or-not agrees  |P(bump) gap|  class agrees  "
          "total variation")
    for name, t in r.strata.items():
        print(f"  {name:<18} {t.pairs:>6}  {f(t.bump_agree):>18}  "
              f"{f(t.bump_gap):>13}  {f(t.class_agree):>12}  {f(t.tv):>15}")
    for name, p in r.policies.items():
        print(f"  policy {name}: P(G) {p.p_goal_rnhql:.2f} here, {p.p_goal_irsim:.2f} "
              f"in IR-SIM over {p.drives} drive(s); primitives to G "
              f"{f(p.primitives_rnhql, 1)} here, {f(p.primitives_irsim, 1)} in IR-SIM")

"""The reward-design experiment: every method x three reward schemes x two discounts.

    python -m scenarios.studies.paper.reward_design --out results/reward-design  # 10 seeds x 3000
    python -m scenarios.studies.paper.reward_design --out /tmp/rd --seeds 2 --episodes 300  # a look
    python -m scenarios.studies.paper.reward_design --out results/reward-design --artifact paper-50
        # ... and write docs/results/reward-design.paper-50.json, the README's table

For each scheme (``paper`` +100/-1/+1, ``goal-only`` +100/-1/0, ``step-cost``
+100/-1/-1) and gamma in {0.95, 0.99}, one ``compare`` sweep on the scenario
(default paper-50) writes its own sub-directory; ``REPORT.md`` puts the table of
final-route-optimal seeds and episodes to a stable optimal route next to the
value-iteration facts of each cell (:mod:`scenarios.studies.paper.reward_facts`),
so every number in the explanation is computed, not typed.
"""

from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from learning.methods.registry import comparison_methods
from scenarios.artifacts import write_artifact
from scenarios.runs.spec import load, make_config
from scenarios.script_args import arg, artifact_arg, jobs_arg, parse, study_command
from scenarios.studies.paper.reward_facts import RewardFacts, facts_markdown, reward_facts
from scenarios.sweep.execute import sweep
from scenarios.sweep.run import make_specs
from sim.files import atomic_write_text
from sim.scenario import REWARD_SCHEMES, Rewards

GAMMAS = (0.95, 0.99)


def cell(entry: dict[str, Any]) -> str:
    """``9/10 · 480`` : optimal seeds, median episodes to a stable optimal route."""
    n = entry["seeds"]
    k = round(entry["optimal_route_fraction"] * n)
    med = entry["episodes_to_stable_optimal"]["median"]
    return f"{k}/{n}" + ("" if med is None else f" · {med:.0f}")


def explain(facts: list[RewardFacts]) -> list[str]:
    """Plain sentences from the computed facts."""
    by = {(f.scheme, f.gamma): f for f in facts}
    out = []
    for g in GAMMAS:
        p, o = by.get(("paper", g)), by.get(("goal-only", g))
        if p is None or o is None:
            continue
        if abs(p.gap) < 1e-6:
            out.append(f"- gamma {g:g}: under `paper` the goal reward equals 1/(1-gamma) = "
                       f"{1 / (1 - g):.4g}, so reaching G is worth exactly as much as "
                       f"wandering forever (V*(S) = {p.v_star_s:.4g}, gap 0 up to value "
                       "iteration's tolerance): every free move is optimal, and no learner can "
                       "prefer the shortest route. Under `goal-only` the gap is "
                       f"{o.gap:.3g}, all of V*(S).")
            continue
        out.append(
            f"- gamma {g:g}: under `paper` the optimal route from S is worth {p.v_star_s:.4g} "
            f"and wandering forever without reaching G {p.v_never_s:.4g}: reaching G is worth "
            f"{p.gap:.3g} more, {100 * p.gap / abs(p.v_star_s):.2g} % of the values a learner "
            f"must estimate. Under `goal-only` the gap is {o.gap:.3g}, all of V*(S), and an "
            f"unexplored value (0) is exactly the value of never reaching G. The smallest gap "
            f"between the best and a worse action along the optimal route is "
            f"{p.action_gap_min:.3g} (`paper`) and {o.action_gap_min:.3g} (`goal-only`).")
    return out


def report(args: Args, methods: list[str], facts: list[RewardFacts],
           grid: dict[tuple[str, float], dict[str, Any]]) -> str:
    lines = ["# Reward design: which scheme lets the learners find the optimal route", "",
             f"Command: `{study_command(__spec__.name, Args, args)}`", "",
             "## What each scheme asks of a learner (value iteration, exact)", "",
             facts_markdown(facts), *explain(facts), "",
             "## What the learners do", "",
             "Cells: seeds whose final greedy route from S is optimal / seeds, then the median "
             "episodes to a stable optimal route (first greedy test from which every later one "
             "is optimal; omitted when the median seed never gets there).", "",
             "| method | " + " | ".join(f"{s} γ={g:g}" for g in GAMMAS for s in REWARD_SCHEMES)
             + " |", "|---|" + "---|" * (len(GAMMAS) * len(REWARD_SCHEMES))]
    for m in methods:
        row = [cell(grid[(s, g)]["summary"][m]["grid"]) for g in GAMMAS for s in REWARD_SCHEMES]
        lines.append(f"| {m} | " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def discounting_methods() -> list[str]:
    """compare's methods that read gamma: the table varies it, and a method that learns no
    discounted values (the references) would refuse it."""
    return [m for m in comparison_methods() if "gamma" in type(make_config(m)).settable()]


@dataclass(frozen=True)
class Args:
    out: str = arg("results/reward-design", "output folder")
    scenario: str = arg("paper-50", "scenario name or file")
    methods: str = arg(",".join(discounting_methods()), "comma-separated methods")
    seeds: int = arg(10, "seeds per cell (0 .. N-1)")
    episodes: int = arg(3000, "episodes per run")
    jobs: int | None = jobs_arg()
    resume: bool = arg(False, "skip runs already finished")
    artifact: str | None = artifact_arg("reward-design")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    methods = [m for m in args.methods.split(",") if m]
    sc, _ = load(args.scenario)
    facts = [reward_facts(sc, s, Rewards.preset(s), g) for g in GAMMAS for s in REWARD_SCHEMES]
    grid: dict[tuple[str, float], dict[str, Any]] = {}
    for g in GAMMAS:
        for s in REWARD_SCHEMES:
            specs = make_specs(args.scenario, methods, list(range(args.seeds)), args.episodes,
                               ["grid"], (("gamma", g),), rewards=s)
            print(f"{s}, gamma {g:g}: {len(specs)} runs", file=sys.stderr)
            grid[(s, g)] = sweep(specs, Path(args.out) / f"{s}-gamma{g:g}",
                                 resume=args.resume, figures=False, jobs=args.jobs)
    text = report(args, methods, facts, grid)
    atomic_write_text(Path(args.out) / "REPORT.md", text)
    if args.artifact:
        write_artifact(f"reward-design.{args.artifact}", study_command(__spec__.name, Args, args),
                       ["grid"],
                       artifact_data(args, methods, facts, grid), study=__file__)
    print(text)
    return 0


def artifact_data(args: Args, methods: list[str], facts: list[RewardFacts],
                  grid: dict[tuple[str, float], dict[str, Any]]) -> dict[str, Any]:
    """What the README's table and sentences show: per method and (scheme, gamma) the
    seeds, the optimal ones and episodes to a stable optimal route; the computed facts."""
    cells = {m: {f"{s} γ={g:g}": {
        "seeds": grid[(s, g)]["summary"][m]["grid"]["seeds"],
        "optimal": round(grid[(s, g)]["summary"][m]["grid"]["optimal_route_fraction"]
                         * grid[(s, g)]["summary"][m]["grid"]["seeds"]),
        "stable": [grid[(s, g)]["summary"][m]["grid"]["episodes_to_stable_optimal"][k]
                   for k in ("median", "q25", "q75")]}
        for g in GAMMAS for s in REWARD_SCHEMES} for m in methods}
    return {"scenario": args.scenario, "seeds": args.seeds, "episodes": args.episodes,
            "columns": [f"{s} γ={g:g}" for g in GAMMAS for s in REWARD_SCHEMES],
            "cells": cells, "facts": [dataclasses.asdict(f) for f in facts],
            "sentences": explain(facts)}


if __name__ == "__main__":
    sys.exit(main())

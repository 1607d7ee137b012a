"""Do the tool's physics grades agree with an independent count? Train, then drive again.

    python -m scenarios.studies.ladder.grading_check --scenario paper-50 --fidelity noisy \\
        --methods rnh-ql+,haql,dyna-q --seeds 10 --episodes 1000 --out results/grading-noisy

Trains every (method, seed) physics run as ``rnhql compare --world physics`` does (one
batched loop, the run's own streams), so each run's ``final_policy`` is the figure the
tool reports. Then each final greedy policy is driven again ``--drives`` times through a
different code path, the single ``gymnasium.make("rnhql/PhysicsRoute-v0")`` env, with noise
streams the tool never uses (seeds 10**6 + k), and the two P(G) are compared: they
agree when the independent count lies in the tool's Wilson 95 % interval or the two
intervals overlap. Writes ``GRADING.md`` and ``grading.json`` to ``--out``.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np

import sim.envs  # noqa: F401  (registers the ids)
from learning.compiled.readout import greedy_actions
from learning.streams import streams
from scenarios.artifacts import write_artifact
from scenarios.runs.physics import RunGroup, train_physics_runs
from scenarios.runs.spec import load, make_config
from scenarios.runs.statistics import quantile
from scenarios.script_args import arg, parse, study_command
from sim.files import atomic_write_text
from sim.physics.fidelity import parse_fidelity
from sim.physics.models.rollouts import wilson_interval

INDEPENDENT_SEED = 10**6


def independent_p_goal(sc, fidelity, policy: np.ndarray, drives: int) -> tuple[int, float]:
    """(drives that reached G, mean primitives of those) through the single gym env."""
    env = gym.make("rnhql/PhysicsRoute-v0", scenario=sc, fidelity=fidelity,
                   max_episode_steps=sc.steps_per_episode)
    hits, prims = 0, []
    for k in range(drives):
        s, _ = env.reset(seed=INDEPENDENT_SEED + k)
        term = trunc = False
        n = 0
        while not (term or trunc):
            s, _, term, trunc, _ = env.step(int(policy[int(s)]))
            n += 1
        if term:
            hits += 1
            prims.append(n)
    env.close()
    return hits, float(np.mean(prims)) if prims else float("nan")


@dataclass(frozen=True)
class Args:
    scenario: str = arg("paper-50", "built-in name or scenario file")
    fidelity: str = arg("noisy", "physics fidelity the runs train and are graded in (a preset "
                        "or a knob file; see rnhql train --help)")
    methods: str = arg("rnh-ql+,haql,dyna-q", "comma-separated methods")
    seeds: int = arg(10, "seeds per method (0 .. N-1)")
    episodes: int = arg(1000, "training episodes per run")
    rewards: str = arg("goal-only", "reward scheme (a preset, or goal=,bump=,step=)")
    drives: int = arg(50, "independent drives of each final policy from S [primitives capped "
                      "at the episode's budget], each its own noise stream")
    out: str = arg("results/grading-check", "output folder")
    artifact: str | None = arg(None, "also write docs/results/physics-grading.NAME.json (a "
                               "table the docs render)", metavar="NAME")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    fid = parse_fidelity(args.fidelity)
    sc, model = load(args.scenario, None, None, args.rewards)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    groups = []
    for m in methods:
        rs = [streams(s) for s in range(args.seeds)]
        groups.append(RunGroup(make_config(m), [r.learner for r in rs],
                               [r.starts for r in rs], [r.physics for r in rs],
                               list(range(args.seeds))))
    results = train_physics_runs(sc, model, groups, args.episodes, 10, fidelity=fid)
    rows, out = [], []
    for m, group in zip(methods, results, strict=True):
        for seed, res in enumerate(group):
            fp = res.world_extras["final_policy"]
            hits, mean_prims = independent_p_goal(sc, fid, greedy_actions(res.agent.state),
                                                  args.drives)
            lo, hi = fp["p_goal_ci95"]
            ilo, ihi = wilson_interval(hits, args.drives)
            agree = lo <= hits / args.drives <= hi or (ilo <= hi and lo <= ihi)
            out.append({"method": m, "seed": seed, "tool": fp,
                        "independent": {"drives": args.drives, "reached": hits,
                                        "p_goal": hits / args.drives,
                                        "p_goal_ci95": [ilo, ihi],
                                        "primitives_mean": mean_prims},
                        "agree": bool(agree)})
            rows.append(f"| {m} | {seed} | {fp['p_goal']:.2f} [{lo:.2f}, {hi:.2f}] | "
                        f"{fp['primitives_mean']} | {hits / args.drives:.2f} [{ilo:.2f}, "
                        f"{ihi:.2f}] | {mean_prims:.1f} | {'yes' if agree else 'NO'} |")
            print(f"done: {m} seed {seed}", file=sys.stderr, flush=True)  # progress only
    cmd = study_command(__spec__.name, Args, args)
    reliable = {m: sum(o["tool"]["p_goal"] >= 0.98 for o in out if o["method"] == m)
                for m in methods}
    lines = [f"# Physics grading on {args.scenario} at `{fid.label}`: the tool's rollouts "
             "against an independent count", "", f"Command: `{cmd}`", "",
             "Tool: the run's `final_policy` (50 drives in the batched world, the run's "
             "rollout streams). Independent: the same greedy policy driven "
             f"{args.drives} times through the single gym env with other noise seeds. "
             "Intervals are Wilson 95 %.", "",
             "Seeds whose final policy reaches G with P ≥ 0.98 (tool): "
             + ", ".join(f"{m} {reliable[m]}/{args.seeds}" for m in methods)
             + f". Agreement: {sum(o['agree'] for o in out)}/{len(out)} policies.", "",
             "| method | seed | tool P(G) | tool primitives | independent P(G) | "
             "independent primitives | agree |", "|---|---|---|---|---|---|---|", *rows]
    text = "\n".join(lines) + "\n"
    outdir = Path(args.out)
    atomic_write_text(outdir / "grading.json", json.dumps(
        {"command": cmd, "fidelity": fid.label, "policies": out}, indent=1))
    atomic_write_text(outdir / "GRADING.md", text)
    if args.artifact:
        write_artifact(f"physics-grading.{args.artifact}", cmd,
                       ["grid", "physics-exact", "physics-noisy"],
                       artifact_data(args, fid.label, methods, out), study=__file__)
    print(text)
    return 0


def artifact_data(args: Args, label: str, methods: list[str],
                  out: list[dict]) -> dict:
    """What the docs' table shows, per method (quantiles over seeds, type 7)."""
    def stats(v: list) -> list:
        return [quantile(v, q) for q in (0.5, 0.25, 0.75)]

    per = {}
    for m in methods:
        rows = [o for o in out if o["method"] == m]
        per[m] = {"seeds": len(rows),
                  "reliable": sum(o["tool"]["p_goal"] >= 0.98 for o in rows),
                  "p_goal": stats([o["tool"]["p_goal"] for o in rows]),
                  "primitives": stats([o["tool"]["primitives_mean"] for o in rows]),
                  "contacts": stats([o["tool"]["contacts_mean"] for o in rows]),
                  "independent_p_goal": stats([o["independent"]["p_goal"] for o in rows]),
                  "agree": sum(o["agree"] for o in rows)}
    return {"scenario": args.scenario, "fidelity": label, "episodes": args.episodes,
            "rewards": args.rewards, "drives": args.drives, "methods": per}


if __name__ == "__main__":
    sys.exit(main())

"""A learner a user brings, against rnh-ql+ in both worlds: the torch DQN of
``examples/batched_dqn.py`` (a batched plain learner) on a 40 x 40 map.

    python -m scenarios.studies.ladder.own_learner --scenario paper-40 --seeds 10 \\
        --episodes 300 --artifact dqn

Runs ``rnhql compare SCENARIO --methods rnh-ql+,examples.batched_dqn:BatchedDQN --world
grid,physics`` through the library (``scenarios.api.compare``: the same runs, streams and
records as the command) and keeps, per method and world: seeds whose final route is
optimal, episodes to a stable optimal route and the success rate (median and quartiles
over seeds), and the training time. docs/python-api.md renders it.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

from scenarios import api
from scenarios.artifacts import write_artifact
from scenarios.runs.statistics import quantile
from scenarios.script_args import arg, parse, study_command

DQN = "examples.batched_dqn:BatchedDQN"


@dataclass(frozen=True)
class Args:
    scenario: str = arg("paper-40", "built-in name or scenario file")
    seeds: int = arg(10, "seeds per method and world (0 .. N-1)")
    episodes: int = arg(300, "training episodes per run")
    rewards: str = arg("goal-only", "reward scheme (a preset, or goal=,bump=,step=)")
    jobs: int = arg(2, "worker processes")
    artifact: str | None = arg(None, "also write docs/results/own-learner.NAME.json (a table "
                               "the docs render)", metavar="NAME")


def _quartiles(values: list[float]) -> list[float | None]:
    vals = sorted(values)
    out = [quantile(vals, q) for q in (0.5, 0.25, 0.75)]
    return [None if v is None or not math.isfinite(v) else v for v in out]


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    root = Path(__file__).resolve().parents[3]
    if str(root) not in sys.path:  # examples/ lives in the source tree, not the wheel
        sys.path.insert(0, str(root))
    # imported here, by name, so the artifact records the learner's code digest (``with``)
    from examples.batched_dqn import BatchedDQN  # noqa: F401

    cmp = api.compare(args.scenario, ["rnh-ql+", DQN], worlds=("grid", "physics"),
                      seeds=args.seeds, episodes=args.episodes, rewards=args.rewards,
                      jobs=args.jobs, progress=True)
    rows = []
    for method in ("rnh-ql+", DQN):
        for world in ("grid", "physics"):
            runs = cmp.of(method, world)
            stable = [math.inf if r.record["episodes_to_stable_optimal"] is None
                      else r.record["episodes_to_stable_optimal"] for r in runs]
            rows.append({"method": method, "name": runs[0].method_name, "world": world,
                         "seeds": len(runs),
                         "optimal": sum(r.final_route_optimal for r in runs),
                         "stable_optimal": _quartiles(stable),
                         "success_rate": _quartiles([r.success_rate for r in runs]),
                         "train_s": _quartiles([r.wall_time_s for r in runs])})
    data = {"scenario": args.scenario, "episodes": args.episodes, "rewards": args.rewards,
            "optimal_route_length": cmp.runs[0].optimal_route_length, "rows": rows}
    print(cmp.summary())
    if args.artifact:
        write_artifact(f"own-learner.{args.artifact}", study_command(__spec__.name, Args, args),
                       ["grid", "physics-exact"], data, study=__file__)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

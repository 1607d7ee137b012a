"""What a plain-Python learner costs, and that it costs the compiled methods nothing.

Run: ``python -m scenarios.bench.plain [--artifact bench]`` (prints JSON; with
``--artifact`` also writes ``docs/results/plain-learner.bench.json``, which
docs/python-api.md renders). On ``paper-50``, goal-only rewards:

* grid: env steps/s of the Python port of ST-QL (``tests/plain_learners/st_ql.py``, the
  learner every per-run figure of ``st-ql`` is tested against), of the same port written
  as a numba ``@jitclass`` (``tests/plain_learners/st_ql_jit.py``, run in a compiled loop)
  and of the compiled ``st-ql`` through the fused kernel, each through
  :func:`learning.drivers.plain_train.train_grid`, the same ``--episodes`` from scratch,
  best of ``--repeats``;
* a batched learner (``tests/plain_learners/st_ql_batched.py``, numpy, one call per step
  for all its runs, drawing what ``st-ql`` draws): ``--batch-seeds`` runs in one lock-step
  batch, grid env steps/s and physics primitives/s over the batch's wall time; the same
  for ST-QL written for numpy's speed (``tests/plain_learners/st_ql_blocks.py``: each run
  draws its numbers in blocks), and its grid rate with ``--wide-batch`` runs in the batch
  (what the per-call cost of numpy becomes when more runs share each call);
* physics at ``exact``: a sweep of ``--seeds`` compiled ``st-ql`` runs alone, then the
  same sweep with as many runs of each port beside them (one worker): the compiled
  runs' primitives per second of their own training time in both, and the ports'.
  A sweep batches Python learners apart from compiled ones
  (:func:`scenarios.runs.physics_batch.plan_tasks`), so the compiled runs keep their pace.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from learning.drivers.plain_batch_train import train_plain_batch
from learning.drivers.plain_train import train_grid
from learning.streams import streams
from scenarios.artifacts import write_artifact
from scenarios.runs.spec import load, make_config
from scenarios.script_args import arg, artifact_arg, parse, study_command
from scenarios.sweep.backends import run_local
from scenarios.sweep.run import make_specs

SCENARIO = "paper-50"
PORT = "tests.plain_learners.st_ql:STQLPort"
JIT_PORT = "tests.plain_learners.st_ql_jit:STQLJit"
BATCHED = "tests.plain_learners.st_ql_batched:STQLBatched"
BLOCKS = "tests.plain_learners.st_ql_blocks:STQLBlocks"


def _port_importable() -> None:
    """The port lives in the source tree's tests (not in the wheel): run from a checkout."""
    root = Path(__file__).resolve().parents[2]
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))


def grid_steps_per_s(method: str, episodes: int, repeats: int) -> float:
    """Best-of-``repeats`` env steps/s of a fresh learner trained ``episodes`` episodes."""
    _, model = load(SCENARIO, rewards="goal-only")
    cfg = make_config(method)
    train_grid(cfg, model, 1, np.random.default_rng(0))  # compile / import outside the clock
    best = 0.0
    for r in range(repeats):
        t0 = time.perf_counter()
        res = train_grid(cfg, model, episodes, np.random.default_rng(r))
        best = max(best, res.env_steps / (time.perf_counter() - t0))
    return best


def physics_rates(seeds: int, episodes: int, port: str | None) -> dict[str, float]:
    """Primitives per second of each method's own training time in a physics sweep: the
    compiled ``st-ql`` alone (``port`` None), or beside ``port`` (the ports are measured in
    sweeps of their own: plain learners share a batch, and its pace)."""
    methods = ["st-ql"] if port is None else ["st-ql", port]
    specs = make_specs(SCENARIO, methods, list(range(seeds)), episodes, ["physics"],
                       rewards="goal-only")
    records = run_local(specs, jobs=1)
    out: dict[str, float] = {}
    for m in methods:
        recs = [r for r in records if r["method"] == m]
        prims = sum(r["env_steps"] for r in recs)
        out[m] = prims / sum(r["wall_time_s"] for r in recs)
    return out


def batched_rates(learner: str, seeds: int, episodes: int,
                  physics_episodes: int | None) -> dict[str, float]:
    """The batched ``learner``'s ``seeds`` runs in one lock-step batch: grid env steps/s
    and (unless ``physics_episodes`` is None) physics primitives/s, each over the batch's
    wall time."""
    _, model = load(SCENARIO, rewards="goal-only")
    cfg = make_config(learner)
    rs = [streams(i) for i in range(seeds)]
    t0 = time.perf_counter()
    runs = train_plain_batch(cfg, model, episodes, [r.learner for r in rs], 10,
                             [r.starts for r in rs])
    out = {"seeds": seeds, "grid": sum(r.env_steps for r in runs) / (time.perf_counter() - t0)}
    if physics_episodes is not None:
        specs = make_specs(SCENARIO, [learner], list(range(seeds)), physics_episodes,
                           ["physics"], rewards="goal-only")
        records = run_local(specs, jobs=1)  # over its own training time, as the rows above
        out["physics"] = (sum(r["env_steps"] for r in records)
                          / sum(r["wall_time_s"] for r in records))
    return out


def measure(episodes: int, repeats: int, seeds: int, physics_episodes: int,
            batch_seeds: int, wide_batch: int) -> dict[str, Any]:
    _port_importable()
    compiled = grid_steps_per_s("st-ql", episodes, repeats)
    port = grid_steps_per_s(PORT, episodes, repeats)
    jit_port = grid_steps_per_s(JIT_PORT, episodes, repeats)
    physics_rates(2, 2, PORT)  # warm: compile, build the physics model
    physics_rates(1, 1, JIT_PORT)  # warm: its compiled physics loop (cache=False: per process)
    alone = physics_rates(seeds, physics_episodes, None)
    beside = physics_rates(seeds, physics_episodes, PORT)
    beside_jit = physics_rates(seeds, physics_episodes, JIT_PORT)
    batched = batched_rates(BATCHED, batch_seeds, episodes // 10, physics_episodes)  # warm
    blocks = batched_rates(BLOCKS, batch_seeds, episodes // 10, physics_episodes)
    blocks["wide"] = batched_rates(BLOCKS, wide_batch, episodes // 10, None)
    return {
        "scenario": SCENARIO, "episodes": episodes, "repeats": repeats,
        "grid": {"st-ql": compiled, "python port": port, "slowdown": compiled / port,
                 "jitclass port": jit_port},
        "physics": {"seeds": seeds, "episodes": physics_episodes,
                    "st-ql alone": alone["st-ql"], "st-ql beside the port": beside["st-ql"],
                    "python port": beside[PORT], "jitclass port": beside_jit[JIT_PORT]},
        "batched": batched,
        "block draws": blocks,
    }


@dataclass(frozen=True)
class Args:
    episodes: int = arg(3000, "grid episodes per run")
    repeats: int = arg(3, "grid runs, the best kept")
    seeds: int = arg(4, "physics runs per method")
    physics_episodes: int = arg(30, "physics episodes per run")
    batch_seeds: int = arg(10, "runs of the batched learner in its one batch")
    wide_batch: int = arg(100, "runs in the wider batch of the block-draws learner (grid)")
    artifact: str | None = artifact_arg("plain-learner")


def main(argv: list[str] | None = None) -> int:
    a = parse(Args, __doc__, argv)
    data = measure(a.episodes, a.repeats, a.seeds, a.physics_episodes, a.batch_seeds,
                   a.wide_batch)
    print(json.dumps(data, indent=1))
    if a.artifact is not None:
        cmd = study_command("scenarios.bench.plain", Args, a)
        write_artifact(f"plain-learner.{a.artifact}", cmd, ["grid", "physics-exact"], data,
                       study=__file__)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

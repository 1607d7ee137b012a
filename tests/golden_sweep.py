"""The fixed sweep whose records must not change when code moves (behaviour unchanged).

Every compared method (:func:`learning.methods.registry.comparison_methods`) and
``rnh-ql+explore``, grid and physics
(exact fidelity), 2 seeds, 100 episodes on ``paper-40`` with goal-only rewards; and the
three model learners in physics at ``noisy`` (2 seeds, 30 episodes), so a change of the
noisy world or its grading shows. The digests of these parts are also the behaviour
digests that tell a table in the docs it is stale (:mod:`scenarios.artifacts`). Each
run's ``results.json`` record, minus its wall-clock fields, is hashed;
``tests/data/golden_sweep.json`` holds the hashes of the code the figures in the README
were measured with.

Regenerate only when a change is *meant* to alter results (and say so in the
commit): ``python -m tests.golden_sweep --write``.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path
from typing import Any

GOLDEN = Path(__file__).parent / "data" / "golden_sweep.json"
SEEDS = (0, 1)
EPISODES = 100
NOISY_METHODS = ("rnh-ql+", "haql", "dyna-q")
NOISY_EPISODES = 30
WALL_KEYS = ("wall_time_s", "wall_time_per_episode_s")
# read-outs added to the record after these digests were measured: the final greedy policy
# (every cell's action) is read from the same trained state the other fields describe, so
# it is left out, and the digests (and the behaviour digests of the docs' tables) stand
# robot_seconds (a physics run's sim_time_per_episode_s summed) likewise
READOUT_KEYS = ("greedy_policy", "robot_seconds")


def sweep_specs() -> list[Any]:
    from learning.methods.registry import METHODS
    from scenarios.sweep.run import make_specs

    # every method of the registry, read from it: a table that ran one goes stale when its
    # behaviour changes (the methods run on request, mf-r-max and the ablation's, too)
    return [*make_specs("paper-40", tuple(METHODS), SEEDS, EPISODES,
                        ("grid", "physics"), rewards="goal-only"),
            *make_specs("paper-40", NOISY_METHODS, SEEDS, NOISY_EPISODES, ("physics",),
                        rewards="goal-only", fidelity="noisy")]


def record_digest(rec: dict[str, Any]) -> str:
    """sha256 of the record's canonical JSON without wall-clock fields and later read-outs."""
    kept = {k: v for k, v in rec.items() if k not in WALL_KEYS + READOUT_KEYS}
    return hashlib.sha256(json.dumps(kept, sort_keys=True).encode()).hexdigest()


def sweep_digests(jobs: int = 1) -> dict[str, str]:
    from scenarios.sweep.backends import run_local

    specs = sweep_specs()
    recs = run_local(specs, jobs=jobs)
    return {rec["key"]: record_digest(rec) for rec in recs}


if __name__ == "__main__":
    digests = sweep_digests(jobs=2)
    if "--write" in sys.argv:
        GOLDEN.write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")
        print(f"wrote {len(digests)} digests to {GOLDEN}")
    else:
        old = json.loads(GOLDEN.read_text())
        bad = sorted(k for k in old if digests.get(k) != old[k])
        print("unchanged" if not bad else "changed:\n  " + "\n  ".join(bad))

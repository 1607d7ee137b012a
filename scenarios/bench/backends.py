"""Runs per second of one sweep on the local process pool and on a local Ray runtime.

    python -m scenarios.bench.backends [--cpus 2]

Both backends run the same 24 independent runs (paper-40, three methods x
8 seeds x 1000 episodes); the figure includes each backend's start-up (worker
processes importing numba and loading the JIT cache; Ray starting its runtime).
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from scenarios.script_args import arg, parse
from scenarios.sweep.execute import BACKENDS, sweep
from scenarios.sweep.run import make_specs


def run_bench(cpus: int = 2) -> dict:
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    specs = make_specs("paper-40", ["rnh-ql", "st-ql", "dyna-q"], list(range(8)), 1000, ["grid"])
    out: dict = {"runs": len(specs), "cpus": cpus}
    with tempfile.TemporaryDirectory() as tmp:
        for name in BACKENDS:
            t0 = time.perf_counter()
            sweep(specs, Path(tmp) / name, backend_name=name, jobs=cpus, figures=False,
                  progress=False)
            dt = time.perf_counter() - t0
            out[f"{name}_s"] = dt
            out[f"{name}_runs_per_s"] = len(specs) / dt
    return out


@dataclass(frozen=True)
class Args:
    cpus: int = arg(2, "CPUs each backend may use")


if __name__ == "__main__":
    print(json.dumps(run_bench(parse(Args, __doc__).cpus), indent=1))

"""Extra wall time of ``--record`` on a real fused-kernel run (not a stand-in loop).

    python -m scenarios.bench.record_overhead

rnh-ql on paper-50, 3000 episodes, median of 5: ``train_tabular`` alone against
``train_tabular`` with the recording observer plus the recorder's close
(flush and footer); creating the recorder (~0.25 s once) is left out.
"""

from __future__ import annotations

import json
import os
import tempfile
import time

import numpy as np

from learning.drivers.train import train_tabular
from scenarios.recording.hooks import GridRecorder, RecordPlan
from scenarios.recording.recorder import Recorder
from scenarios.runs.spec import load, make_config


def run_bench(repeats: int = 5) -> dict:
    sc, model = load("paper-50")
    cfg = make_config("rnh-ql")
    train_tabular(cfg, model, 10, np.random.default_rng(0))  # JIT warm
    out = {}
    for every in (10, 100):
        plain, recorded = [], []
        for rep in range(repeats):
            t0 = time.perf_counter()
            train_tabular(cfg, model, 3000, np.random.default_rng(rep))
            plain.append(time.perf_counter() - t0)
            with tempfile.TemporaryDirectory() as tmp:
                rec = Recorder.create(os.path.join(tmp, "r.rrd"), sc, model, method="rnh-ql",
                                      config=cfg, seed=rep)
                t0 = time.perf_counter()
                train_tabular(cfg, model, 3000, np.random.default_rng(rep),
                              observer=GridRecorder(rec, RecordPlan(3000, every=every)))
                rec.close()
                recorded.append(time.perf_counter() - t0)
        p, r = float(np.median(plain)), float(np.median(recorded))
        out[f"every_{every}"] = {"plain_s": p, "recorded_s": r, "overhead": r / p - 1}
    return out


if __name__ == "__main__":
    print(json.dumps(run_bench(), indent=1))

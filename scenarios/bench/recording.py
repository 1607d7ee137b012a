"""What recording costs: ``python -m scenarios.bench.recording [--episodes 3000]``.

A stand-in training loop spins for ``--episode-ms`` per episode on one core (the
fused kernels take ~0.2 ms per episode); every ``--every``-th episode a
``--steps``-move trajectory is recorded, metrics go out in batches of
``--batch`` episodes and value maps every ``--values-every`` episodes. The
buffer is flushed every ``--flush-every`` episodes (as the row/time limits of
a real run would) and timed on its own. Costs are CPU time of the training
thread (robust on a busy machine); the process total adds Rerun's background
encoder threads, which need a second core to stay out of the way.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scenarios.recording.recorder import Recorder
from scenarios.script_args import arg, parse
from sim.grid import build_model
from sim.scenario_io import resolve_scenario


def spin(seconds: float) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def random_walk(model, rng: np.random.Generator, steps: int) -> np.ndarray:
    acts = rng.integers(0, 4, steps)
    out = np.empty(steps + 1, dtype=np.int64)
    s = out[0] = model.start
    for i, a in enumerate(acts.tolist()):
        s = model.next_state[s, a]
        out[i + 1] = s
    return out


@dataclass(frozen=True)
class Args:
    scenario: str = arg("paper-50", "built-in name or .toml path")
    episodes: int = arg(3000, "stand-in training episodes")
    every: int = arg(10, "record every N-th episode")
    steps: int = arg(600, "moves per recorded episode")
    batch: int = arg(100, "episodes per metric batch")
    values_every: int = arg(100, "episodes between value maps")
    flush_every: int = arg(1000, "episodes between flushes")
    episode_ms: float = arg(0.2, "stand-in training time per episode [ms]")


def run(a: Args, record: bool, out: Path) -> dict[str, float]:
    sc = resolve_scenario(a.scenario)
    model = build_model(sc)
    rng = np.random.default_rng(0)
    walks = [random_walk(model, rng, a.steps) for _ in range(8)]
    q = rng.normal(size=(model.n_states, 4))
    v = rng.normal(size=model.n_states)
    cost = {"traj": 0.0, "metrics": 0.0, "values": 0.0, "flush": 0.0}
    count = dict.fromkeys(cost, 0)
    clock = time.thread_time
    w = time.perf_counter()
    rec = (Recorder.create(out, sc, model, method="bench", config={}, seed=0,
                           flush_rows=10**12, flush_interval_s=1e12) if record else None)
    create_s = time.perf_counter() - w

    def timed(name: str, fn, *args, **kw) -> None:
        t = clock()
        fn(*args, **kw)
        cost[name] += clock() - t
        count[name] += 1

    t0, cpu0 = time.perf_counter(), time.process_time()
    for ep in range(a.episodes):
        spin(a.episode_ms / 1e3)
        if rec is None:
            continue
        if ep % a.every == 0:
            timed("traj", rec.log_episode_trajectory, ep, walks[ep % len(walks)])
        if (ep + 1) % a.batch == 0:
            e = np.arange(ep + 1 - a.batch, ep + 1)
            timed("metrics", rec.log_episode_metrics, e, np.full(a.batch, a.steps),
                  np.zeros(a.batch, bool), np.full(a.batch, float(a.steps)),
                  wall_time_s=np.full(a.batch, a.episode_ms / 1e3),
                  shaping_mean=np.zeros(a.batch), shaping_std=np.ones(a.batch))
        if (ep + 1) % a.values_every == 0:
            timed("values", rec.log_values, ep, q, v_nn=v)
        if (ep + 1) % a.flush_every == 0:
            timed("flush", rec.flush)
    if rec is not None:
        timed("flush", rec.close)
    return {"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - cpu0,
            "create_s": create_s, "cost": cost, "count": count,
            "size_kib": out.stat().st_size / 1024 if record else 0.0}


def main() -> None:
    a = parse(Args, __doc__)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.rrd"
        base = run(a, record=False, out=out)
        rec = run(a, record=True, out=out)
    train_s = a.episodes * a.episode_ms / 1e3
    c, n = rec["cost"], rec["count"]
    main_s = sum(c.values())
    ms = {k: 1e3 * c[k] / max(n[k], 1) for k in c}
    print(f"{a.episodes} episodes x {a.episode_ms} ms = {train_s:.2f} s of training; recording "
          f"every {a.every}th ({a.steps} moves), metrics per {a.batch}, values per "
          f"{a.values_every}, flush per {a.flush_every}; file {rec['size_kib']:.0f} KiB")
    print(f"  training-thread CPU of recording: {1e3 * main_s:.1f} ms = "
          f"{100 * main_s / train_s:.1f} % of the training time")
    print(f"    log_episode_trajectory {ms['traj']:.4f} ms x {n['traj']}, "
          f"log_episode_metrics {ms['metrics']:.4f} ms x {n['metrics']}, "
          f"log_values {ms['values']:.3f} ms x {n['values']}, "
          f"flush {ms['flush']:.2f} ms x {n['flush']} (incl. close)")
    print(f"    per recorded episode incl. its share of the flushes: "
          f"{1e3 * (c['traj'] + c['flush']) / max(n['traj'], 1):.3f} ms")
    cpu = rec["cpu_s"] - base["cpu_s"]
    print(f"  process CPU incl. Rerun's encoder threads: +{cpu:.3f} s = "
          f"{100 * cpu / train_s:.1f} %; wall {base['wall_s']:.2f} -> {rec['wall_s']:.2f} s "
          f"(create {rec['create_s']:.2f} s once, not counted)")


if __name__ == "__main__":
    main()

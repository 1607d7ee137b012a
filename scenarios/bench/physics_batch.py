"""Benchmark of the batched physics world (measured, never asserted).

* ``scaling``: random primitives per second on one core against the batch size (1 to
  1024 robots in one Space) on paper-50 and on a 512 x 512 arena at paper-50's obstacle
  density; random walks from random start cells, restarted every 200 primitives, the
  guard cache warmed first (a learning run fills it in its first episodes);
* ``learning``: a learning run as ``compare --world physics`` runs it: the compared methods x
  ``seeds`` seeds, ``episodes`` episodes, all robots of one batch in this process (one
  core), with the time split between learners, the compiled world kernel, Chipmunk
  (casts and contact checks), episode bookkeeping and the rest of the loop.

Run: ``python -m scenarios.bench.physics_batch [--quick] [--plot FILE.png]
[--artifact NAME]``;
``rnhql bench --physics`` includes it.
"""

from __future__ import annotations

import json
import os
import platform
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from learning.methods.registry import comparison_methods
from learning.streams import streams
from scenarios.artifacts import ROOT, load_artifact, write_artifact
from scenarios.bench.build import arena_toml
from scenarios.bench.physics import _round
from scenarios.figures.save import save_figure
from scenarios.runs.physics import RunGroup, train_physics_runs
from scenarios.runs.spec import load, make_config
from scenarios.script_args import arg, artifact_arg, parse
from sim.grid import build_model
from sim.physics.fidelity import parse_fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.scenario import Scenario
from sim.scenario_io import resolve_scenario

SIZES = (1, 4, 16, 64, 256, 1024)


def arena_512() -> Scenario:
    """The 512 x 512 arena of ``scenarios.bench.build`` (seeded circles, paper-50 density)."""
    with tempfile.TemporaryDirectory() as d:
        return resolve_scenario(str(arena_toml(512, Path(d))))


def primitives_per_s(sc: Scenario, n_robots: int, seconds: float, seed: int = 0,
                     fidelity: str | None = None) -> dict:
    """Random primitives per second through :meth:`RouteBatch.step` with ``n_robots`` (at
    ``fidelity``: each robot its own noise stream), with the kernel's own time and its
    geometry queries per primitive."""
    model = build_model(sc)
    rng = np.random.default_rng(seed)
    batch = RouteBatch(sc, n_robots, fidelity=parse_fidelity(fidelity))
    for i in range(n_robots):
        batch.set_noise_rng(i, np.random.default_rng([seed, i]))

    def restart() -> None:
        for i, s0 in enumerate(rng.choice(model.start_states, n_robots)):
            x, y = batch.disc.state_centre(int(s0))
            batch.place(i, x, y, 0.0)

    restart()
    for _ in range(max(20, 2000 // n_robots)):  # warm the guard cache and the JIT
        batch.step(rng.integers(0, 4, n_robots))
    casts0, checks0 = batch.casts, batch.checks
    k0, c0, q0 = batch.kernel_s, batch.chipmunk_s, int(batch.scratch.counters[0])
    n = steps = 0
    t = time.perf_counter()
    while time.perf_counter() - t < seconds:
        restart()
        for _ in range(200):
            out = batch.step(rng.integers(0, 4, n_robots))
            steps += int(out.steps.sum())
        n += 200 * n_robots
    el = time.perf_counter() - t
    return {"robots": n_robots, "primitives_per_s": n / el,
            "physics_steps_per_primitive": steps / n,
            "casts_per_primitive": (batch.casts - casts0) / n,
            "checks_per_primitive": (batch.checks - checks0) / n,
            "kernel_us_per_primitive": 1e6 * (batch.kernel_s - k0) / n,
            "geometry_queries_per_primitive": (int(batch.scratch.counters[0]) - q0) / n,
            "kernel_fraction": (batch.kernel_s - k0) / el,
            "chipmunk_fraction": (batch.chipmunk_s - c0) / el}


def scaling(seconds: float = 2.0, sizes: tuple[int, ...] = SIZES) -> dict[str, Any]:
    maps = {"paper-50": resolve_scenario("paper-50"), "arena-512": arena_512()}
    return {name: {str(n): primitives_per_s(sc, n, seconds) for n in sizes}
            for name, sc in maps.items()}


def learning(episodes: int = 300, seeds: int = 10, scenario: str = "paper-50",
             rewards: str = "goal-only", methods: tuple[str, ...] | None = None,
             fidelity: str | None = None) -> dict:
    """One batch of ``len(methods) x seeds`` runs, as a physics compare trains them
    (``methods``: by default those ``rnhql compare`` runs)."""
    sc, model = load(scenario, None, None, rewards)
    methods = comparison_methods() if methods is None else methods
    groups = []
    for m in methods:
        rs = [streams(s) for s in range(seeds)]
        groups.append(RunGroup(make_config(m), [r.learner for r in rs], [r.starts for r in rs],
                               [r.physics for r in rs]))
    # every method's kernels compiled first: on a cold numba cache the timed run would
    # otherwise count compilation as learning
    warm = [RunGroup(g.cfg, [streams(0).learner], [streams(0).starts], [streams(0).physics])
            for g in groups]
    train_physics_runs(sc, model, warm, 1, 1, fidelity=parse_fidelity(fidelity))
    split: dict[str, float] = {}
    t = time.perf_counter()
    train_physics_runs(sc, model, groups, episodes, 10, split=split,
                       fidelity=parse_fidelity(fidelity))
    el = time.perf_counter() - t
    prims = split.pop("primitives")
    loop = el - split["final"]
    return {"runs": len(methods) * seeds, "episodes": episodes, "primitives": prims,
            "fidelity": parse_fidelity(fidelity).label,
            "seconds": el, "primitives_per_s_training": prims / loop,
            "primitives_per_s_with_final_routes": prims / el,
            "split_s": split, "split_fraction_of_training": {
                k: v / loop for k, v in split.items() if k != "final"}}


def run_bench(quick: bool = False) -> dict[str, Any]:
    """The scaling of random primitives, and the learning run at ``exact`` and at ``noisy``
    (the rung the ladder study trains most at: every step above exact has its own guard)."""
    return {"scaling": scaling(0.5 if quick else 2.0,
                               (1, 16, 256) if quick else SIZES),
            "learning": learning(30 if quick else 300),
            "learning_noisy": learning(10 if quick else 100, fidelity="noisy")}


def plot(figures: dict[str, Any], path: Path) -> None:
    # lazy: matplotlib costs 270 ms at import; rnhql bench --physics imports this module
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for name, rows in figures["scaling"].items():
        n = [int(k) for k in rows]
        ax.plot(n, [rows[k]["primitives_per_s"] for k in rows], "o-", label=name)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("robots in one Space")
    ax.set_ylabel("primitives per second (one core)")
    ax.set_title("Batched physics world: random primitives, exact fidelity")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def figure_from_artifact(name: str, path: Path) -> None:
    """Redraw the scaling plot from artifact ``name`` (``rnhql report --figures``)."""
    plot(load_artifact(name)["data"], path)


@dataclass(frozen=True)
class Args:
    quick: bool = arg(False, "shorter timings, 30 episodes")
    episodes: int | None = arg(None, "episodes of the learning run (default 300; 30 with "
                               "--quick)")
    plot: str | None = arg(None, "write the scaling plot here")
    artifact: str | None = artifact_arg("physics-batch")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)

    load_before = os.getloadavg()[0]  # other work on the machine skews every timing
    figs = {"scaling": scaling(0.5 if args.quick else 2.0, (1, 16, 256) if args.quick else SIZES),
            "learning": learning(args.episodes or (30 if args.quick else 300))}
    if args.plot is not None:
        plot(figs, Path(args.plot))
    if args.artifact:
        figs["machine"] = {"cores": os.cpu_count(), "cpu": platform.processor() or
                           platform.machine(), "python": platform.python_version(),
                           "load_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)]}
        cmd = ("python -m scenarios.bench.physics_batch" + (" --quick" if args.quick else "")
               + ("" if args.episodes is None else f" --episodes {args.episodes}")
               + f" --artifact {args.artifact}")
        write_artifact(f"physics-batch.{args.artifact}", cmd, ["physics-exact"], _round(figs),
                       study=__file__)
        figure_from_artifact(f"physics-batch.{args.artifact}", ROOT / "docs" / "physics_batch.png")
    print(json.dumps(_round(figs), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

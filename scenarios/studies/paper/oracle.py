"""The oracle bound of RNH-QL's family: the best potential its network could ever represent.

    python -m scenarios.studies.paper.oracle --out results/oracle   # paper-50, 10 seeds x 3000

RNH-QL shapes a Q-table with Phi = V_NN, a linear network over Gaussian RBF
features. However well it is trained, Phi is at best the least-squares fit of
the exact V* (value iteration) in the span of those features. So Q-learning
with that fitted V* as a *static* potential (F = gamma Phi(s') - Phi(s), the
PFH-RL rule, Phi(G) = 0) bounds what any member of the family can reach with
those features. Rows, per reward scheme: the exact V* (no approximation at all),
its fit by the paper's 10 x 10 lattice, its fit by a lattice every 4 cells
(rnh-ql+'s spacing, dense here), and no shaping. Same protocol as everywhere:
greedy test from S every 10 episodes, common random numbers per seed.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from learning.compiled.kernels import run_episodes
from learning.drivers.state import init_state
from learning.drivers.train import KERNEL_OUT, greedy_test
from learning.geometry import geometry_of
from learning.methods.pfh_rl import PFHRL
from learning.metrics import episodes_to_stable_optimal
from learning.parts.rbf import rbf_features
from learning.streams import streams
from scenarios.artifacts import write_artifact
from scenarios.runs.spec import load
from scenarios.runs.statistics import quantile
from scenarios.script_args import arg, artifact_arg, parse, study_command
from sim.files import atomic_write_text
from sim.grid.planning import value_iteration


def fitted(v_star: np.ndarray, phi: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Least-squares fit of V* over the free, goal-reaching states, in span(phi)."""
    w, *_ = np.linalg.lstsq(phi[free], v_star[free], rcond=None)
    return phi @ w


def train_with_potential(model, potential: np.ndarray, seed: int, episodes: int,
                         gamma: float) -> tuple[bool, int | None]:
    """Q-learning + static shaping by ``potential``; (final route optimal, stable after)."""
    cfg = PFHRL(gamma=gamma)
    rs = streams(seed)
    st = init_state(cfg, geometry_of(model), rs.learner)
    st.phi[:] = potential - potential[model.goal]  # Phi(G) = 0
    tests_e, tests_l = [], []
    out = tuple(np.zeros(10, dtype=np.int32 if f == "steps" else bool if f == "success"
                         else np.float64) for f in KERNEL_OUT)
    done = 0
    while done < episodes:
        n = min(10, episodes - done)
        run_episodes(st, model, n, rs.learner, tuple(a[:n] for a in out),
                     start_rng=rs.starts)
        done += n
        tests_e.append(done)
        tests_l.append(greedy_test(st, model)[0])
    opt = model.optimal_route_length
    return tests_l[-1] == opt, episodes_to_stable_optimal(np.array(tests_e),
                                                          np.array(tests_l), opt)


@dataclass(frozen=True)
class Args:
    out: str = arg("results/oracle", "output folder")
    scenario: str = arg("paper-50", "scenario name or file")
    seeds: int = arg(10, "seeds per cell (0 .. N-1)")
    episodes: int = arg(3000, "episodes per run")
    gamma: float = arg(0.95, "discount")
    artifact: str | None = artifact_arg("oracle")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    rows: list[dict] = []
    lines = [f"# Oracle bound on {args.scenario}: Q-learning shaped by the best potential each "
             "feature set can represent", "",
             f"Command: `{study_command(__spec__.name, Args, args)}`", "",
             "Cells: seeds whose final greedy route is optimal / seeds · median [q25, q75] "
             "episodes to a stable optimal route. `fit error` is the mean absolute error of the "
             "fitted potential against V* over the free states, and V*(S) sets its scale.", "",
             "| rewards | potential | fit error | V*(S) | result |", "|---|---|---|---|---|"]
    for scheme in ("paper", "goal-only"):
        _, model = load(args.scenario, None, None, scheme)
        v_star, _ = value_iteration(model.next_state, model.reward, model.terminal, args.gamma)
        free = model.distance_to_goal >= 0
        geom = geometry_of(model)
        k4 = max(2, round(model.nx / 4))
        potentials = {
            "exact V*": v_star,
            "V* fitted by 10x10 RBF (rnh-ql)": fitted(
                v_star, rbf_features(geom.coords, geom.bounds_m, 10), free),
            f"V* fitted by {k4}x{k4} RBF (a centre every 4 cells)": fitted(
                v_star, rbf_features(geom.coords, geom.bounds_m, k4), free),
            "none (Q-learning)": np.zeros_like(v_star),
        }
        for name, pot in potentials.items():
            runs = [train_with_potential(model, pot, s, args.episodes, args.gamma)
                    for s in range(args.seeds)]
            stable = [r[1] for r in runs]
            med, q25, q75 = (quantile(stable, q) for q in (0.5, 0.25, 0.75))

            def f(v: float) -> str:
                return "never" if not np.isfinite(v) else f"{v:.0f}"

            err = float(np.mean(np.abs(pot[free] - v_star[free])))
            rows.append({"rewards": scheme, "potential": name, "fit_error": err,
                         "v_star_s": float(v_star[model.start]), "seeds": args.seeds,
                         "optimal": int(sum(r[0] for r in runs)),
                         "stable": [None if not np.isfinite(v) else float(v)
                                    for v in (med, q25, q75)]})
            lines.append(f"| {scheme} | {name} | {err:.3g} | {v_star[model.start]:.3g} | "
                         f"{sum(r[0] for r in runs)}/{args.seeds} · {f(med)} [{f(q25)}, "
                         f"{f(q75)}] |")
            print(f"done: {scheme}, {name}", file=sys.stderr, flush=True)  # progress only
    text = "\n".join(lines) + "\n"
    atomic_write_text(Path(args.out) / "ORACLE.md", text)
    if args.artifact:
        write_artifact(f"oracle.{args.artifact}", study_command(__spec__.name, Args, args),
                       ["grid"],
                       {"scenario": args.scenario, "episodes": args.episodes,
                        "gamma": args.gamma, "rows": rows}, study=__file__)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Does IR-SIM agree? The same (cell, action) primitives, and the same policies, in both.

:func:`crosscheck` draws (cell, action) pairs in three strata of the grid's own answer
(the grid blocks the move; it is free but the cell lies next to a blocked one; free in the
open), a third each, drives each pair ``repeats`` times from its cell's centre (a heading
drawn from the four cardinal ones, the same in both simulators) in the batched kernel
(:class:`sim.physics.kernel.batch.RouteBatch`) and in IR-SIM
(:class:`sim.physics.crosscheck.irsim_world.IrSimRobot`), and compares per pair:

- bump or not: the share of pairs whose majority outcome agrees, and the mean gap between
  the two P(bump);
- the outcome class (bumped or not, and the cell it ends in): the share of pairs whose
  most frequent class agrees, and the mean total variation distance between the two class
  distributions (0: identical, 1: disjoint);

and, for each policy given, P(G) and the mean primitives of the drives that reach G, from
S within the episode budget, in both. At ``exact`` nothing is random: every drive of a
pair is the same, and agreement is per primitive.
"""

from __future__ import annotations

import collections
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from sim.grid import TabularModel
from sim.physics.crosscheck.irsim_world import IrSimRobot, check_rung
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

STRATA = ("grid-blocked", "free-near-obstacle", "free-open")
CROSSCHECK_TAG = 7  # the rollout streams' tag of a crosscheck's policy drives


@dataclass(frozen=True)
class CrosscheckOptions:
    """How much to drive (counts), and the seed of the pairs, headings and noise."""

    pairs: int = 60  # (cell, action) pairs, a third from each stratum where there are enough
    repeats: int = 4  # drives per pair in each simulator (1 at exact: it is deterministic)
    policy_drives: int = 5  # drives of each policy from S in each simulator
    seed: int = 0


def grid_optimal_policy(model: TabularModel) -> np.ndarray:
    """int[nS]: in every cell that reaches G, a move to a neighbour one BFS step nearer G (the
    lowest-numbered such action): the grid's optimal policy, a policy anyone can rebuild."""
    dist = model.distance_to_goal
    nxt = model.next_state
    policy = np.zeros(model.n_states, dtype=np.int64)
    for s in np.flatnonzero(dist > 0).tolist():
        for a in range(nxt.shape[1]):
            if dist[nxt[s, a]] == dist[s] - 1 and nxt[s, a] != s:
                policy[s] = a
                break
    return policy


def strata(model: TabularModel) -> dict[str, np.ndarray]:
    """(cell, action) pairs (as ``state * 4 + action``) of every cell that reaches G, by
    stratum (:data:`STRATA`)."""
    cells = np.asarray(model.start_states, dtype=np.int64)
    blocked = model.blocked
    ny, nx = blocked.shape
    near = np.zeros(cells.size, dtype=bool)
    for k, s in enumerate(cells.tolist()):
        x, y = s % nx, s // nx
        near[k] = blocked[max(y - 1, 0):y + 2, max(x - 1, 0):x + 2].any() or x in (0, nx - 1) \
            or y in (0, ny - 1)
    pairs = (cells[:, None] * 4 + np.arange(4)[None, :]).ravel()
    s, a = pairs // 4, pairs % 4
    stays = model.next_state[s, a] == s
    near_pair = np.repeat(near, 4)
    return {"grid-blocked": pairs[stays], "free-near-obstacle": pairs[~stays & near_pair],
            "free-open": pairs[~stays & ~near_pair]}


def draw_pairs(model: TabularModel, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` pairs (at most every pair there is), a third from each stratum; where one is
    short, the others make up the rest."""
    by = [strata(model)[name] for name in STRATA]
    sizes = [p.size for p in by]
    take = [0] * len(by)
    left = min(n, sum(sizes))
    while left:
        open_ = [k for k in range(len(by)) if take[k] < sizes[k]]
        for k in open_[:left]:
            take[k] += 1
        left -= min(left, len(open_))
    return np.concatenate([rng.choice(p, t, replace=False) if t else p[:0]
                           for p, t in zip(by, take, strict=True)])


def _drive_ours(sc: Scenario, fid: Fidelity, cfg: PhysicsConfig, starts: np.ndarray,
                actions: np.ndarray, seeds: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Each (start pose, action) once in the batched kernel: (bumped, end state)."""
    n = actions.size
    batch = RouteBatch(sc, n, cfg, fidelity=fid, contact_records=False)
    for i in range(n):
        batch.set_noise_rng(i, np.random.default_rng(seeds[i]))
        batch.place(i, *starts[i])
    out = batch.step(actions)
    return out.bumped.copy(), out.state.copy()


def _classes(bumped: np.ndarray, states: np.ndarray) -> list[tuple[bool, int]]:
    return [(bool(b), int(s)) for b, s in zip(bumped.tolist(), states.tolist(), strict=True)]


def _tv(a: list, b: list) -> float:
    ca, cb = collections.Counter(a), collections.Counter(b)
    return 0.5 * sum(abs(ca[k] / len(a) - cb[k] / len(b)) for k in set(ca) | set(cb))


def crosscheck(sc: Scenario, model: TabularModel, fid: Fidelity,
               options: CrosscheckOptions = CrosscheckOptions(),
               policies: dict[str, np.ndarray] | None = None,
               config: PhysicsConfig | None = None) -> dict[str, Any]:
    """The agreement figures of the module doc, per stratum and overall."""
    check_rung(fid)
    cfg = config or PhysicsConfig()
    rng = np.random.default_rng(options.seed)
    repeats = 1 if fid.is_exact else options.repeats
    pairs = draw_pairs(model, options.pairs, rng)
    stratum_of = {int(p): name for name, ps in strata(model).items() for p in ps.tolist()}
    n = pairs.size * repeats
    states, actions = np.repeat(pairs // 4, repeats), np.repeat(pairs % 4, repeats)
    starts = np.zeros((n, 3))
    for i in range(n):
        x, y = model.coords[states[i]]
        starts[i] = (x, y, float(rng.integers(4)) * math.pi / 2)
    seeds = [int(v) for v in rng.integers(0, 2**62, n)]
    t0 = time.perf_counter()
    ours_b, ours_s = _drive_ours(sc, fid, cfg, starts, actions, seeds)
    t1 = time.perf_counter()
    robot = IrSimRobot(sc, fid, cfg, seed=options.seed)
    theirs_b = np.zeros(n, dtype=bool)
    theirs_s = np.zeros(n, dtype=np.int64)
    for i in range(n):
        robot.reseed(seeds[i])
        robot.place(*starts[i])
        theirs_b[i], _, theirs_s[i] = robot.drive(int(actions[i]))
    t2 = time.perf_counter()
    rows: dict[str, dict[str, list[float]]] = {name: collections.defaultdict(list)
                                               for name in (*STRATA, "all")}
    for k, pair in enumerate(pairs.tolist()):
        sl = slice(k * repeats, (k + 1) * repeats)
        a, b = _classes(ours_b[sl], ours_s[sl]), _classes(theirs_b[sl], theirs_s[sl])
        pa, pb = float(ours_b[sl].mean()), float(theirs_b[sl].mean())
        mode_a = collections.Counter(a).most_common(1)[0][0]
        mode_b = collections.Counter(b).most_common(1)[0][0]
        for name in (stratum_of[pair], "all"):
            r = rows[name]
            r["bump_agree"].append(float((pa >= 0.5) == (pb >= 0.5)))
            r["bump_gap"].append(abs(pa - pb))
            r["class_agree"].append(float(mode_a == mode_b))
            r["tv"].append(_tv(a, b))
            r["p_bump_ours"].append(pa)
            r["p_bump_irsim"].append(pb)
    keys = ("bump_agree", "bump_gap", "class_agree", "tv", "p_bump_ours", "p_bump_irsim")
    table = {name: {"pairs": len(r["tv"]),
                    **{key: (float(np.mean(r[key])) if r[key] else None) for key in keys}}
             for name, r in rows.items()}  # a stratum the map lacks: no pairs, no figures
    result: dict[str, Any] = {
        "scenario": sc.name, "fidelity": fid.label, "pairs": int(pairs.size),
        "repeats": repeats, "primitives": int(n), "seed": options.seed,
        "strata": table, "seconds": {"rnhql": round(t1 - t0, 3), "irsim": round(t2 - t1, 3)},
        "policies": {}}
    for name, policy in (policies or {}).items():
        result["policies"][name] = _policy(sc, model, fid, cfg, policy, options, robot)
    return result


def _policy(sc: Scenario, model: TabularModel, fid: Fidelity, cfg: PhysicsConfig,
            policy: np.ndarray, options: CrosscheckOptions, robot: IrSimRobot
            ) -> dict[str, Any]:
    """P(G) and the mean primitives of the drives that reach G, from S, in both."""
    from sim.physics.models.rollouts import drive_policy

    drives = 1 if fid.is_exact else options.policy_drives
    ours = drive_policy(sc, policy, fid, drives, options.seed, CROSSCHECK_TAG, config=cfg)
    x0, y0 = model.coords[model.start]
    reached, lengths = [], []
    for d in range(drives):
        robot.reseed(options.seed * 1000 + d)
        robot.place(float(x0), float(y0), 0.0)
        state, k = model.start, 0
        while state != model.goal and k < model.max_steps:
            _, _, state = robot.drive(int(policy[state]))
            k += 1
        reached.append(state == model.goal)
        if state == model.goal:
            lengths.append(k)
    ours_len = ours.primitives[ours.reached]
    return {"drives": drives, "p_goal_rnhql": float(ours.p_goal),
            "p_goal_irsim": float(np.mean(reached)),
            "primitives_rnhql": float(np.mean(ours_len)) if ours_len.size else None,
            "primitives_irsim": float(np.mean(lengths)) if lengths else None}

"""Driving a policy from S many times at a fidelity: the check of the stochastic model.

The model (:mod:`sim.physics.models.stochastic`) abstracts a continuous pose into
``(cell, context, particle)``; whether that abstraction holds is an empirical question,
answered by driving. :func:`drive_cell_policy` and :func:`drive_model_policy` drive ``n``
episodes from S (its centre, heading +x, as the env's reset), each rollout with its own
noise stream (``SeedSequence(seed)``'s ``i``-th child), as the robots of
:class:`sim.physics.kernel.batch.RouteBatch` (256 at a time), each until G or the step budget.
A learner's policy has one action per cell; the model's optimal policy one per state,
and the driver finds the robot's state as the build does (its cell, the context the
last primitive left it in, the particle nearest to where it rests).

Agreement (``tests/test_stochastic_model.py``, and paper-40 in the README): the model's
P(G within budget) of a policy is within :data:`P_TOL` (0.05) of the share of driven
rollouts that reach G, and its mean primitives of the episodes that reach G within the
budget within :func:`primitives_tolerance` (max(1 primitive, 5 %)) of the rollouts'
mean, with at least 200 rollouts. At ``exact`` one rollout is the deterministic route.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sim.grid.discretiser import Discretiser
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.models.stochastic import Locator, StochasticModel, next_context, start_context
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

BATCH = 256  # robots per batched world
P_TOL = 0.05  # model vs rollouts: P(G within budget) [-]
REL_TOL = 0.05  # model vs rollouts: mean primitives, relative part [-]
ABS_TOL = 1.0  # model vs rollouts: mean primitives, absolute floor [primitives]


def primitives_tolerance(mean: float) -> float:
    """How far the model's mean primitives may be from the rollouts': max(1, 5 %)."""
    return max(ABS_TOL, REL_TOL * mean)


@dataclass(frozen=True)
class RolloutStats:
    """What ``n`` driven episodes from S did."""

    n: int  # rollouts
    budget: int  # step budget per rollout [primitives]
    p_goal: float  # share that reached G within the budget [-]
    mean_primitives: float  # over the rollouts that reached G; nan if none [primitives]
    median_primitives: float  # over the rollouts that reached G; nan if none [primitives]
    mean_contacts: float  # contacts that began, per rollout [-]
    off_model: int  # primitives from a state the model does not have (action 0 taken)

    @property
    def p_goal_interval(self) -> tuple[float, float]:
        """The 95 % Wilson interval on ``p_goal``."""
        z, n, p = 1.96, self.n, self.p_goal
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
        return max(0.0, centre - half), min(1.0, centre + half)


# chooser(cells, contexts, poses, active) -> (actions int64[N], off-model count)
Chooser = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, int]]


def drive_cell_policy(sc: Scenario, fidelity: Fidelity | None, pi: np.ndarray, n: int = 200,
                      seed: int = 0, budget: int | None = None,
                      config: PhysicsConfig | None = None) -> RolloutStats:
    """Drive ``pi`` (int[nCells]: one action per cell, whatever the context) from S."""
    pi = np.asarray(pi, dtype=np.int64)
    if pi.shape != (sc.nx * sc.ny,) or pi.min(initial=0) < 0 or pi.max(initial=0) > 3:
        raise ValueError(f"pi must be int[{sc.nx * sc.ny}] of actions 0..3")
    return _drive(sc, fidelity, lambda cells, _c, _p, _a: (pi[cells], 0), n, seed, budget,
                  config)


def drive_model_policy(sc: Scenario, model: StochasticModel, policy: np.ndarray,
                       n: int = 200, seed: int = 0, budget: int | None = None,
                       config: PhysicsConfig | None = None) -> RolloutStats:
    """Drive ``policy`` (int[model.n_states]: one action per model state, e.g.
    :attr:`sim.physics.models.solve.Optimum.policy`) at the model's fidelity."""
    policy = np.asarray(policy, dtype=np.int64)
    if policy.shape != (model.n_states,):
        raise ValueError(f"policy must be int[{model.n_states}]")
    locate = Locator(model)

    def choose(cells, contexts, poses, active):
        acts = np.zeros(cells.size, dtype=np.int64)
        off = 0
        for i in np.flatnonzero(active).tolist():
            s = locate.state(int(cells[i]), int(contexts[i]), poses[i])
            if 0 <= s < model.n_states:
                acts[i] = policy[s]
            else:
                off += 1
        return acts, off

    return _drive(sc, model.fidelity, choose, n, seed, budget, config)


def _drive(sc: Scenario, fidelity: Fidelity | None, choose: Chooser, n: int, seed: int,
           budget: int | None, config: PhysicsConfig | None) -> RolloutStats:
    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"n must be an int >= 1, got {n!r}")
    fid = fidelity or Fidelity()
    budget = sc.steps_per_episode if budget is None else budget
    disc = Discretiser.from_scenario(sc)
    goal, start = disc.index(*sc.goal), disc.index(*sc.start)
    x0, y0 = disc.cell_centre(*sc.start)
    children = np.random.SeedSequence(seed).spawn(n)
    primitives = np.full(n, -1, dtype=np.int64)  # -1: G not reached within the budget
    contacts = np.zeros(n, dtype=np.int64)
    off = 0
    world = RouteBatch(sc, min(BATCH, n), config, fidelity=fid, contact_records=False)
    for lo in range(0, n, world.n):
        m = min(world.n, n - lo)
        for i in range(m):
            world.set_noise_rng(i, np.random.default_rng(children[lo + i]))
            world.place(i, x0, y0, 0.0)
        cell = np.full(world.n, start, dtype=np.int64)
        ctx = np.full(world.n, start_context(fid), dtype=np.int64)
        active = np.zeros(world.n, dtype=bool)
        active[:m] = start != goal
        mine = primitives[lo:lo + m]  # a view: rollouts lo .. lo + m
        if start == goal:
            mine[:] = 0
        for t in range(1, budget + 1):
            if not active.any():
                break
            acts, missed = choose(cell, ctx, world.poses(), active)
            off += missed
            out = world.step(acts, active)
            contacts[lo:lo + m] += out.contacts[:m]
            cell = np.where(active, out.state, cell)
            ctx = np.where(active, next_context(out, acts, fid), ctx)
            done = active & (cell == goal)
            mine[done[:m]] = t
            active &= ~done
    hit = primitives[primitives >= 0]
    return RolloutStats(
        n=n, budget=budget, p_goal=float(hit.size / n),
        mean_primitives=float(hit.mean()) if hit.size else math.nan,
        median_primitives=float(np.median(hit)) if hit.size else math.nan,
        mean_contacts=float(contacts.mean()), off_model=off)

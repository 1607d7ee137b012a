"""V*: the optimum of a driven stochastic model, and what a given policy achieves in it.

The problem is a stochastic shortest path: every primitive costs 1, G is absorbing and
free, V*(s) is the expected number of primitives to G under the best policy. Value
iteration for it converges to V* only when every policy it may pick is *proper* (reaches
G with probability 1); an improper one (a robot that can bump in a corner forever) has
infinite cost, and VI from V = 0 would creep towards it without end. So the solve runs in
two steps:

1. the states from which G can be reached with probability 1 under some policy, and per
   state the actions that keep that possible (every outcome stays inside the set): the
   classical almost-sure reachability fixpoint (e.g. de Alfaro 1997; Baier & Katoen,
   "Principles of Model Checking", 10.6), on the model's support;
2. value iteration on those states and actions only (V* is infinite elsewhere).

Outside that set the policy takes, per state, the action that maximises the probability
of reaching G within the step budget (finite-horizon VI of that probability), so a
stationary policy is defined everywhere.

Two figures per policy, from S: the expected primitives to G (infinite when G is not
reached with probability 1) and P(G within the episode's step budget)
(``scenario.steps_per_episode``), a finite-horizon evaluation that also gives the mean
primitives of the episodes that reach G within the budget, the figure a driven rollout
measures. A learner's policy has one action per cell; :func:`evaluate_cell_policy` plays
it in every context of that cell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.grid.actions import N_ACTIONS
from sim.grid.model import TabularModel
from sim.physics.models.stochastic import StochasticModel

VI_TOL = 1e-9  # value iteration stops when no value moves by more than this [primitives]
MAX_SWEEPS = 200_000  # a bound on VI sweeps (a model needs a few hundred to a few thousand)


@dataclass(frozen=True)
class PolicyValue:
    """What a policy achieves from S in the model."""

    expected_primitives: float  # E[primitives to G]; inf when G is not reached w.p. 1
    p_goal_within_budget: float  # P(G within `budget` primitives) [-]
    mean_primitives_within_budget: float  # E[primitives | G within budget]; nan if P = 0
    budget: int  # the step budget [primitives]


@dataclass(frozen=True, eq=False)
class Optimum:
    """V* and an optimal stationary policy of a :class:`StochasticModel`."""

    value: np.ndarray  # float64[n + 1]: V* [expected primitives]; inf where G is not sure
    policy: np.ndarray  # int64[n]: an optimal action per state
    sure: np.ndarray  # bool[n + 1]: G reachable with probability 1 under some policy
    start: PolicyValue  # V*(S) and P(G within budget) under `policy`, from S
    sweeps: int  # value-iteration sweeps to converge


def _edges(model: StochasticModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return model.src_sa, model.dst.astype(np.int64), model.prob


def almost_sure(model: StochasticModel, allowed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sure bool[n + 1], ok bool[4n]): the states from which G is reached with probability 1
    using ``allowed`` (bool[4n]) actions, and the allowed actions that keep every outcome in
    that set. The fixpoint: drop actions with an outcome outside the set, keep the states
    that can still reach G with positive probability, repeat until nothing changes."""
    n = model.n_states
    src_sa, dst, _ = _edges(model)
    sure = np.ones(n + 1, dtype=bool)
    while True:
        ok = allowed & np.repeat(sure[:n], N_ACTIONS)
        ok[src_sa[~sure[dst]]] = False
        use = ok[src_sa]
        e_src, e_dst = src_sa[use] // N_ACTIONS, dst[use]
        reach = np.zeros(n + 1, dtype=bool)
        reach[n] = True
        count = 1
        while True:
            reach[e_src[reach[e_dst]]] = True
            new = int(reach.sum())
            if new == count:
                break
            count = new
        if np.array_equal(reach, sure):
            return sure, ok
        sure = reach


def _backup(model: StochasticModel, v: np.ndarray) -> np.ndarray:
    """float64[n, 4]: 1 + E[V(next)] per (state, action)."""
    src_sa, dst, prob = _edges(model)
    q = np.bincount(src_sa, prob * v[dst], minlength=N_ACTIONS * model.n_states)
    return 1.0 + q.reshape(-1, N_ACTIONS)


def _iterate(model: StochasticModel, ok: np.ndarray, sure: np.ndarray,
             policy: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """V on the ``sure`` states by value iteration over ``ok`` actions (or evaluation of
    ``policy``), from V = 0 upwards; inf elsewhere."""
    n = model.n_states
    v = np.where(sure, 0.0, math.inf)
    v[n] = 0.0
    mask = ~ok.reshape(n, N_ACTIONS)
    for sweep in range(1, MAX_SWEEPS + 1):
        q = _backup(model, np.where(sure, v, 0.0))  # states outside `sure` never reached via ok
        q[mask] = math.inf
        new = q.min(axis=1) if policy is None else q[np.arange(n), policy]
        new = np.where(sure[:n], new, math.inf)
        delta = np.abs(new[sure[:n]] - v[:n][sure[:n]])
        v[:n] = new
        if delta.size == 0 or delta.max() <= VI_TOL:
            return v, sweep
    raise RuntimeError(f"value iteration did not converge in {MAX_SWEEPS} sweeps")


def horizon(model: StochasticModel, policy: np.ndarray, budget: int) -> tuple[float, float]:
    """(P(G within ``budget``), E[primitives | G within budget]) from S under ``policy``."""
    n, start = model.n_states, model.start
    if start == n:
        return 1.0, 0.0
    src_sa, dst, prob = _edges(model)
    use = (src_sa % N_ACTIONS) == policy[src_sa // N_ACTIONS]
    e_src, e_dst, e_p = src_sa[use] // N_ACTIONS, dst[use], prob[use]
    p = np.zeros(n + 1)
    p[n] = 1.0
    hit = np.zeros(budget + 1)
    for t in range(1, budget + 1):
        p = np.bincount(e_src, e_p * p[e_dst], minlength=n + 1)
        p[n] = 1.0
        hit[t] = p[start]
    total = float(hit[budget])
    first = np.diff(hit)  # P(G first reached at primitive t), t = 1..budget
    mean = float((np.arange(1, budget + 1) * first).sum() / total) if total > 0 else math.nan
    return min(total, 1.0), mean


def _best_reach(model: StochasticModel, budget: int) -> np.ndarray:
    """int64[n]: per state the action maximising P(G within ``budget``)."""
    n = model.n_states
    src_sa, dst, prob = _edges(model)
    p = np.zeros(n + 1)
    p[n] = 1.0
    q = np.zeros((n, N_ACTIONS))
    for _ in range(budget):
        q = np.bincount(src_sa, prob * p[dst], minlength=N_ACTIONS * n).reshape(n, N_ACTIONS)
        p[:n] = q.max(axis=1)
    return q.argmax(axis=1)


def solve(model: StochasticModel, budget: int) -> Optimum:
    """V*, an optimal policy (ties: the lowest action index) and its figures from S."""
    n = model.n_states
    sure, ok = almost_sure(model, np.ones(N_ACTIONS * n, dtype=bool))
    v, sweeps = _iterate(model, ok, sure)
    q = _backup(model, np.where(sure, v, 0.0))
    q[~ok.reshape(n, N_ACTIONS)] = math.inf
    policy = q.argmin(axis=1)
    if not sure[:n].all():
        policy = np.where(sure[:n], policy, _best_reach(model, budget))
    p, mean = horizon(model, policy, budget)
    start = PolicyValue(float(v[model.start]), p, mean, budget)
    return Optimum(value=v, policy=policy, sure=sure, start=start, sweeps=sweeps)


def evaluate_policy(model: StochasticModel, policy: np.ndarray, budget: int) -> PolicyValue:
    """What ``policy`` (int[n], one action per state) achieves from S."""
    n = model.n_states
    policy = np.asarray(policy, dtype=np.int64)
    allowed = np.zeros((n, N_ACTIONS), dtype=bool)
    allowed[np.arange(n), policy] = True
    sure, ok = almost_sure(model, allowed.ravel())
    v, _ = _iterate(model, ok, sure, policy)
    p, mean = horizon(model, policy, budget)
    return PolicyValue(float(v[model.start]), p, mean, budget)


def evaluate_cell_policy(model: StochasticModel, pi: np.ndarray, budget: int) -> PolicyValue:
    """What a learner's policy ``pi`` (int[nCells]: one action per cell, whatever the
    context) achieves from S."""
    pi = np.asarray(pi, dtype=np.int64)
    if pi.shape != (model.nx * model.ny,) or pi.min(initial=0) < 0 or \
            pi.max(initial=0) >= N_ACTIONS:
        raise ValueError(f"pi must be int[{model.nx * model.ny}] of actions 0..3")
    return evaluate_policy(model, pi[model.state_cell], budget)


def shortest_route_policy(tab: TabularModel) -> np.ndarray:
    """int64[nCells]: per cell the first action (in index order) that moves one step closer to
    G in a deterministic tabular model (e.g. the exact physics model); 0 where none does."""
    d = tab.distance_to_goal
    nxt_d = d[tab.next_state]
    better = (d[:, None] > 0) & (nxt_d >= 0) & (nxt_d == d[:, None] - 1)
    return np.where(better.any(axis=1), better.argmax(axis=1), 0).astype(np.int64)

"""Geometric heuristics and abstract-state shaping: PFH-RL, HAQL, SARSA-RS.

The precomputations use only :class:`learning.geometry.Geometry` (cell centres,
goal, bounds, cell size), never the dynamics, so they are the same knowledge an
agent would have in the physics world. All shaping here is potential-based
(Ng 1999) with Phi(goal) = 0, which keeps the optimal policy unchanged.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from learning import kinds as K
from learning.geometry import Geometry
from learning.rules import record_shaping, sarsa


def manhattan_cells(geom: Geometry) -> np.ndarray:
    """int64[nS]: Manhattan distance to the goal in cells (ignores obstacles)."""
    cells = geom.cells
    return np.abs(cells - cells[geom.goal]).sum(axis=1)


def pfh_potential(geom: Geometry, scale: float) -> np.ndarray:
    """float64[nS, 1]: Phi(s) = -scale * Manhattan cells to G (so Phi(goal) = 0)."""
    return (-scale * manhattan_cells(geom).astype(np.float64))[:, None].copy()


def heuristic_actions(geom: Geometry) -> np.ndarray:
    """int32[nS, 1]: pi_H(s), the move that most reduces the Manhattan distance to G.

    Both axes usually reduce it by one cell; the move is then along the axis with
    more cells left (x on equal), so pi_H follows a straight-ish diagonal
    staircase. At the goal: action 0.
    """
    d = geom.cells[geom.goal] - geom.cells  # cells still to go (dx, dy)
    dx, dy = d[:, 0], d[:, 1]
    along_x = np.abs(dx) >= np.abs(dy)
    act_x = np.where(dx > 0, 3, 2)
    act_y = np.where(dy > 0, 0, 1)
    pi = np.where(along_x, act_x, act_y)
    pi[(dx == 0) & (dy == 0)] = 0
    return pi.astype(np.int32)[:, None].copy()


def abstract_states(geom: Geometry, block: int) -> tuple[np.ndarray, int]:
    """(z int32[nS, 1], n_z): each cell's block x block abstract cell, row-major."""
    if block < 1:
        raise ValueError(f"SARSA-RS block must be >= 1 cell, got {block}")
    cells = geom.cells
    nbx = -(-(int(cells[:, 0].max()) + 1) // block)
    nby = -(-(int(cells[:, 1].max()) + 1) // block)
    z = (cells[:, 1] // block) * nbx + cells[:, 0] // block
    return z.astype(np.int32)[:, None].copy(), nbx * nby


@njit(cache=True)
def static_shaping(phi, s, s2, terminated, gamma):
    """F = gamma * Phi(s') - Phi(s), Phi(s') = 0 on termination."""
    p2 = 0.0 if terminated else phi[s2, 0]
    return gamma * p2 - phi[s, 0]


@njit(cache=True)
def sarsa_rs(q, v, z, ivar, fvar, s, a, r, s2, a2, terminated, alpha, gamma, omega, alpha_v):
    """SARSA with F = gamma*omega*V(z(s')) - omega*V(z(s)) (V before this step's update), then
    SMDP TD on the abstract V.

    ``fvar[F_R]`` / ``fvar[F_GK]`` accumulate the discounted reward R and gamma^k
    since the agent entered its abstract state z(s); when z(s') != z(s) or the
    episode terminates: V(z) += alpha_v * (R + gamma^k V(z') [not terminated] - V(z)).
    """
    zs = z[s, 0]
    zs2 = z[s2, 0]
    p2 = 0.0 if terminated else omega * v[zs2]
    f = gamma * p2 - omega * v[zs]
    record_shaping(ivar, fvar, f)
    sarsa(q, s, a, r, s2, a2, terminated, alpha, gamma, f)
    fvar[K.F_R] += fvar[K.F_GK] * r
    fvar[K.F_GK] *= gamma
    if terminated or zs2 != zs:
        target = fvar[K.F_R]
        if not terminated:
            target += fvar[K.F_GK] * v[zs2]
        v[zs] += alpha_v * (target - v[zs])
        fvar[K.F_R] = 0.0
        fvar[K.F_GK] = 1.0

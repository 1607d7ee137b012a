"""Q-learning shaped by the value of a coarser abstraction of the map (``abstraction-ql``;
after Cipollone, Jonsson, Ronca & Favorito, AAAI 2023).

Potential-based shaping (Ng, Harada & Russell 1999) with Φ(s) = the value of s's abstract
state in an abstract MDP solved in advance: the arena's ``block`` x ``block``-cell blocks,
a block free when any of its cells is free in the map given in advance
(:attr:`learning.geometry.Geometry.map_prior`), two blocks linked when a free cell of one
is a move from a free cell of the other. The abstract distance D(z) to G's block, in
blocks, is one BFS; Φ(s) = ``omega`` · gamma^(block · D(z(s))), the discounted goal
reward over the route the abstraction promises (0 where no abstract route exists). The
ground learner is Q-learning with F = gamma · Φ(s') - Φ(s) (Φ(G) = 0 on arrival), so its
optimal policy is the unshaped one's: the rules of :mod:`learning.methods.pfh_rl`, which
runs any config that brings a static Φ (this module is the config and its Φ only).

This is the modern form of SARSA-RS's coarse-grid Φ (:mod:`learning.methods.sarsa_rs`
learns its abstract values online); Cipollone et al. assume the abstraction is given, and
so does this method: **it knows the map coarsely before the first step, which no other
method here does**. Its row says what such a prior is worth to a model-free learner. With
no map given (``map_prior`` None) every block is free and Φ is a coarse free-space distance.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from learning.config import MethodConfig
from learning.geometry import ACTION_DELTAS, Geometry


@dataclass(frozen=True)
class AbstractionQL(MethodConfig):
    """Q-learning + shaping Φ = the value of a coarse abstraction of a map given in advance."""

    name: ClassVar[str] = "ABSTRACTION-QL"
    cli: ClassVar[str] = "abstraction-ql"
    block: int = 8  # abstract cell side [cells]
    omega: float = 100.0  # Φ at G's block [reward units]; the built-in schemes' goal reward

    def potential(self, geom: Geometry) -> np.ndarray:
        """Φ(s) = omega · gamma^(block · D(z(s))), 0 where the abstraction has no route."""
        z, dist = abstract_distances(geom, self.block)
        d = dist[z]
        return np.where(d >= 0, self.omega * self.gamma ** (self.block * np.maximum(d, 0)), 0.0)


def abstract_distances(geom: Geometry, block: int) -> tuple[np.ndarray, np.ndarray]:
    """(z int64[nS]: each cell's block, D int64[n_z]: moves between blocks to G's block, -1
    where no abstract route exists) of the map given in advance."""
    cells = geom.cells
    nbx = -(-(int(cells[:, 0].max()) + 1) // block)
    nby = -(-(int(cells[:, 1].max()) + 1) // block)
    z = (cells[:, 1] // block) * nbx + cells[:, 0] // block
    free = (np.ones(geom.n_states, np.bool_) if geom.map_prior is None
            else np.asarray(geom.map_prior, np.bool_))
    index = {(int(x), int(y)): i for i, (x, y) in enumerate(cells)}
    links: list[set[int]] = [set() for _ in range(nbx * nby)]
    for i in np.flatnonzero(free):
        x, y = int(cells[i, 0]), int(cells[i, 1])
        for dx, dy in ACTION_DELTAS:
            j = index.get((x + dx, y + dy))
            if j is not None and free[j] and z[j] != z[i]:
                links[int(z[i])].add(int(z[j]))
    dist = np.full(nbx * nby, -1, np.int64)
    g = int(z[geom.goal])
    dist[g] = 0
    todo = deque([g])
    while todo:
        a = todo.popleft()
        for b in links[a]:  # links are symmetric: a move and its reverse
            if dist[b] < 0:
                dist[b] = dist[a] + 1
                todo.append(b)
    return z.astype(np.int64), dist

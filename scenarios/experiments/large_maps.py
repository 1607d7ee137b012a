"""Seeded maps of 256 x 256 cells and more, of the kinds route learning is judged on.

Only one public map of that size is shipped (``Berlin_1_256``, a city), so the
other kinds are generated, each from a seed, as ``free[row, col]`` arrays in the
Moving AI frame (row 0 at the top), and written as ``.map`` files:

* ``maze``: a lattice maze with corridors ``corridor`` cells wide and 1-cell
  walls, ``braid`` of its inner walls knocked out (loops, several routes);
* ``rooms``: rooms ``room`` cells wide behind 1-cell walls, one or two doors of
  1-3 cells in each wall between neighbours;
* ``random``: single blocked cells at a density (Moving AI's random-*-20 kind);
* ``caves``: a game-like map, open areas joined by narrow passages (a cellular
  automaton over random noise, 5 rounds of the 4-5 rule);
* ``city``: ``Berlin_1_256`` as it is at 256, and each cell as 2 x 2 at 512
  (the same streets, twice the states: the only city at that size here).

Every generator keeps only the largest 4-connected component free, so every
free cell can reach every other.
"""

from __future__ import annotations

import numpy as np

from scenarios.experiments.suite import room_grid, spanning_tree
from sim.grid.planning import grid_distances
from sim.maps import read_free_grid

KINDS = ("city", "maze", "rooms", "random", "caves")


def largest_component(free: np.ndarray) -> np.ndarray:
    """free with every cell outside its largest 4-connected component blocked."""
    left = free.copy()
    best = np.zeros_like(free)
    while left.any():
        r, c = np.argwhere(left)[0]
        comp = grid_distances(left, (int(c), int(r))) >= 0
        if comp.sum() > best.sum():
            best = comp
        left &= ~comp
        if best.sum() * 2 >= free.sum():
            break
    return best


def maze(size: int, seed: int, corridor: int = 3, braid: float = 0.05) -> np.ndarray:
    rng = np.random.default_rng(seed)
    pitch = corridor + 1
    n = (size - 1) // pitch
    lattice = np.zeros(size, dtype=bool)  # the rows (and columns) of the corridors
    for k in range(n):
        lattice[k * pitch + 1:k * pitch + 1 + corridor] = True
    free = np.outer(lattice, lattice)
    for (r, c), (nr, nc) in spanning_tree(n, rng):
        _open(free, r, c, nr, nc, pitch, corridor)
    walls = [(r, c, r + dr, c + dc) for r in range(n) for c in range(n)
             for dr, dc in ((1, 0), (0, 1)) if r + dr < n and c + dc < n]
    for i in rng.permutation(len(walls))[:int(braid * len(walls))]:
        _open(free, *walls[i], pitch, corridor)
    return largest_component(free)


def _open(free: np.ndarray, r: int, c: int, nr: int, nc: int, pitch: int, corridor: int) -> None:
    """Knock out the wall between lattice cells (r, c) and (nr, nc)."""
    if nr != r:
        row = max(r, nr) * pitch
        free[row, c * pitch + 1:c * pitch + 1 + corridor] = True
    else:
        col = max(c, nc) * pitch
        free[r * pitch + 1:r * pitch + 1 + corridor, col] = True


def rooms(size: int, seed: int, room: int = 15) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return largest_component(room_grid(size, (size - 1) // (room + 1), room, 3, rng))


def random_cells(size: int, seed: int, density: float = 0.2) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return largest_component(rng.random((size, size)) >= density)


def caves(size: int, seed: int, fill: float = 0.45, rounds: int = 5) -> np.ndarray:
    """Open areas and narrow passages (a game map's kind): random rock at ``fill``, then
    ``rounds`` of the 4-5 rule, a cell is rock if 5 or more of its 8 neighbours are, or if
    it is rock and 4 are (the border counts as rock). About two thirds stays free."""
    rng = np.random.default_rng(seed)
    rock = rng.random((size, size)) < fill
    for _ in range(rounds):
        padded = np.pad(rock, 1, constant_values=True)
        count = sum(padded[1 + dr:size + 1 + dr, 1 + dc:size + 1 + dc]
                    for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dr, dc) != (0, 0))
        rock = (count >= 5) | (rock & (count >= 4))
    return largest_component(~rock)


def city(size: int, seed: int = 0) -> np.ndarray:
    """Berlin_1_256 (the seed is unused: the streets are the map's), scaled up by whole
    cells to ``size`` (256 or a multiple)."""
    from scenarios.experiments.suite import MAPS_DIR

    free = read_free_grid(MAPS_DIR / "Berlin_1_256.map")
    f = size // free.shape[0]
    if f < 1 or f * free.shape[0] != size:
        raise ValueError(f"city maps come in multiples of {free.shape[0]} cells, not {size}")
    return largest_component(np.kron(free, np.ones((f, f), dtype=bool)).astype(bool))


GENERATORS = {"city": city, "maze": maze, "rooms": rooms, "random": random_cells,
              "caves": caves}


def generate(kind: str, size: int, seed: int) -> np.ndarray:
    if kind not in GENERATORS:
        raise ValueError(f"unknown map kind {kind!r}: use one of {', '.join(GENERATORS)}")
    return GENERATORS[kind](size, seed)

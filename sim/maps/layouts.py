"""Obstacle layouts generated from parameters: seeded random circles, chains of posts."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from sim.errors import ScenarioError
from sim.feasibility import validate
from sim.scenario import Circle, Scenario


def random_circles(sc: Scenario, count: int, radius_min_m: float, radius_max_m: float,
                   rng: np.random.Generator, keep_clear_m: float = 1.5,
                   max_layouts: int = 100) -> tuple[Circle, ...]:
    """Draw ``count`` circles that keep S and G free and connected.

    Circles are rejected one by one if they come within ``keep_clear_m`` of the
    start or goal centre; a finished layout that disconnects S from G is dropped
    whole and redrawn (rare at the densities used here, and cheaper than a BFS
    per circle). Deterministic for a given generator state.
    """
    c = sc.cell_size_m
    keep = [((ix + 0.5) * c, (iy + 0.5) * c) for ix, iy in (sc.start, sc.goal)]
    for _ in range(max_layouts):
        circles: list[Circle] = []
        tries = 0
        while len(circles) < count and tries < 100 * count:
            tries += 1
            r = float(rng.uniform(radius_min_m, radius_max_m))
            x = float(rng.uniform(0.0, sc.width_m))
            y = float(rng.uniform(0.0, sc.height_m))
            if all(math.hypot(x - kx, y - ky) > r + sc.robot.inflation_m + keep_clear_m
                   for kx, ky in keep):
                circles.append(Circle(x, y, r))
        if len(circles) < count:  # never a silent layout with fewer circles than asked for
            raise ScenarioError(sc.source, "obstacles.random.count",
                                f"only {len(circles)} of {count} circles fit in "
                                f"{100 * count:,} draws while keeping S and G clear",
                                f"ask for at most {len(circles)} circles, or smaller ones")
        candidate = replace(sc, obstacles=sc.obstacles + tuple(circles))
        try:
            validate(candidate)
        except ScenarioError:
            continue
        return tuple(circles)
    raise ScenarioError(sc.source, "obstacles.random", f"no connected layout in {max_layouts} "
                        "tries", "use fewer or smaller circles")


def chain(start_m: tuple[float, float], end_m: tuple[float, float], radius_m: float,
          spacing_m: float) -> tuple[Circle, ...]:
    """Circles of one radius every ``spacing_m`` along a segment: a wall made of posts."""
    (x0, y0), (x1, y1) = start_m, end_m
    n = max(1, math.floor(math.hypot(x1 - x0, y1 - y0) / spacing_m))
    return tuple(Circle(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, radius_m)
                 for k in range(n + 1))

"""The compiled swept-disc guard gives Chipmunk's answer (pymunk's segment queries)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.physics.kernel.sweep import Sweeper
from sim.physics.reference.world import PhysicsWorld
from sim.physics.static import sweep_alpha
from sim.scenario_io import resolve_scenario


@pytest.mark.parametrize("name", ["paper-50", "arena", "zigzag-50"])
def test_sweep_fraction_equals_chipmunk(name):
    """Random segments over the whole arena (walls, circles, blocked cells; starts inside
    shapes included), the robot's radius and larger ones."""
    sc = resolve_scenario(name)
    world = PhysicsWorld(sc)
    sweeper = Sweeper(sc)
    rng = np.random.default_rng(1)
    hits = 0
    for _ in range(4000):
        ax, ay = rng.uniform(-1, sc.width_m + 1), rng.uniform(-1, sc.height_m + 1)
        ang, length = rng.uniform(0, 2 * math.pi), rng.uniform(0.01, 3.0)
        bx, by = ax + length * math.cos(ang), ay + length * math.sin(ang)
        radius = float(rng.choice([sc.robot.radius_m, 0.5, 1.2]))
        want = sweep_alpha(world.space, world._query_filter, radius, ax, ay, bx, by)
        got = sweeper.fraction(radius, ax, ay, bx, by)
        if want is None:
            assert got == math.inf, (ax, ay, bx, by, radius)
        else:
            hits += 1
            assert got == pytest.approx(want, abs=1e-12), (ax, ay, bx, by, radius)
    assert hits > 300  # plenty of segments do touch something

"""The compiled swept-disc guard gives Chipmunk's answer (pymunk's segment queries)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from sim.physics.fidelity import parse_fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.kernel.queries import CLEAR_MARGIN_M, new_clear_region
from sim.physics.kernel.state import Geometry, Params, Scratch
from sim.physics.kernel.sweep import Sweeper, overlap_depth, static_geometry
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


@njit(cache=False)
def _regions(robots, pt, geo_t, st, xy):
    """new_clear_region at each pose of ``xy``: rows (ball x, y, r, box x0, y0, x1, y1)."""
    p, g, s = Params(*pt), Geometry(*geo_t), Scratch(*st)
    out = np.zeros((xy.shape[0], 7))
    rb = robots[0]
    for i in range(xy.shape[0]):
        rb.x, rb.y = xy[i, 0], xy[i, 1]
        new_clear_region(rb, p, g, s)
        out[i] = (rb.clear_x, rb.clear_y, rb.clear_r, rb.box_x0, rb.box_y0, rb.box_x1,
                  rb.box_y1)
    return out


@pytest.mark.parametrize("name", ["paper-50", "maze-1", "rooms-1"])
def test_every_centre_in_a_clear_region_keeps_the_margin(name):
    """The kernel skips a step's sweep and touch checks inside the robot's clear ball or
    box; that is only right if every centre in them leaves the disc at least
    CLEAR_MARGIN_M from every static shape (measured here by brute force over every shape,
    at random centres inside regions built from random poses)."""
    sc = resolve_scenario(name)
    batch = RouteBatch(sc, 1, fidelity=parse_fidelity("noisy"), contact_records=False)
    rng = np.random.default_rng(3)
    xy = np.column_stack([rng.uniform(0, sc.width_m, 400), rng.uniform(0, sc.height_m, 400)])
    pt, _, geo_t, st = batch._args
    regions = _regions(batch.robots, pt, geo_t, st, xy)
    g = static_geometry(sc)
    seen = np.zeros(len(g.circles) + len(g.boxes), np.int64)
    r = sc.robot.radius_m + CLEAR_MARGIN_M * (1 - 1e-6)
    boxes = balls = 0
    for k, (cx, cy, cr, x0, y0, x1, y1) in enumerate(regions):
        points = []
        if cr > 0:
            balls += 1
            ang, rad = rng.uniform(0, 2 * math.pi, 20), cr * np.sqrt(rng.uniform(0, 1, 20))
            points += list(zip(cx + rad * np.cos(ang), cy + rad * np.sin(ang), strict=True))
        if x1 > x0:
            boxes += 1
            assert x0 < xy[k, 0] < x1 and y0 < xy[k, 1] < y1  # the pose is in its box
            points += list(zip(rng.uniform(x0, x1, 20), rng.uniform(y0, y1, 20), strict=True))
            points += [(x0, y0), (x1, y1), (x0, y1), (x1, y0)]  # its corners too
        for px, py in points:
            seen[:] = 0
            depth = overlap_depth(g.circles, g.walls, g.boxes, g.cell_m, g.nx, g.ny, g.start,
                                  g.items, seen, 1, r, px, py)
            assert depth <= 0.0, (name, k, px, py, depth)
    assert boxes >= balls / 2 > 20, (boxes, balls)  # most poses in free space have a box

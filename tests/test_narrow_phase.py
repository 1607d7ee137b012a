"""The compiled narrow phase (sim.physics.kernel.narrow_phase) is Chipmunk's shape query: the same
shapes touched, the same new contacts for a resting robot, the same contact points,
normals and depths, on circles, walls and blocked-cell boxes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.physics.kernel.batch import RouteBatch
from sim.physics.kernel.narrow_phase import TOUCH_BAND_M, contact_buffer, contacts_began
from sim.physics.static import CollisionType, contact_of
from sim.scenario_io import resolve_scenario


def chipmunk_contacts(batch: RouteBatch, x: float, y: float, exclude: frozenset = frozenset()
                      ) -> list[tuple]:
    """What Chipmunk's shape query says of the disc at (x, y): (kind, point, normal, depth)
    of every shape it touches but those in ``exclude``."""
    out = []
    for info in touching(batch, x, y):
        if info.shape in exclude:
            continue
        c = contact_of(0, info.shape.collision_type, info.contact_point_set)
        out.append((int(c.kind), c.x_m, c.y_m, c.normal_x, c.normal_y, c.depth_m))
    return sorted(out)


def touching(batch: RouteBatch, x: float, y: float) -> list:
    batch.r.x[0], batch.r.y[0], batch.r.th[0] = x, y, 0.0
    batch.sync_body(0)
    return batch.space.shape_query(batch.shapes[0])


def booked(out: np.ndarray, n: int) -> list[tuple]:
    return sorted((int(c[1]), *c[2:]) for c in out[:n].tolist())


def assert_same(got: list[tuple], want: list[tuple]) -> None:
    assert [c[0] for c in got] == [c[0] for c in want]
    if got:
        np.testing.assert_allclose(np.array(got)[:, 1:], np.array(want)[:, 1:], rtol=0,
                                   atol=1e-12)


def near_surface_poses(batch: RouteBatch, rng: np.random.Generator, n: int) -> np.ndarray:
    """Disc centres within 5 mm of touching a random static shape (either side)."""
    g, r = batch.static, batch.radius_m
    poses = []
    while len(poses) < n:
        u = rng.uniform(-0.005, 0.005)
        kind = rng.integers(3)
        if kind == 0 and len(g.circles):
            cx, cy, cr = g.circles[rng.integers(len(g.circles))]
            a = rng.uniform(0, 2 * math.pi)
            x, y = cx + (cr + r + u) * math.cos(a), cy + (cr + r + u) * math.sin(a)
        elif kind == 1 and len(g.boxes):
            x0, y0, x1, y1 = g.boxes[rng.integers(len(g.boxes))]
            px, py = rng.uniform(x0, x1), rng.uniform(y0, y1)
            side = rng.integers(4)  # a face or, half the time, towards a corner
            d = r + u
            x, y = ((x0 - d, py), (x1 + d, py), (px, y0 - d), (px, y1 + d))[side]
            if rng.random() < 0.5:
                cxn, cyn = (x0 if x < px else x1), (y0 if y < py else y1)
                a = math.atan2(y - cyn, x - cxn)
                x, y = cxn + d * math.cos(a), cyn + d * math.sin(a)
        else:
            w, h = batch.scenario.width_m, batch.scenario.height_m
            along = rng.uniform(r, w - r)
            x, y = ((along, r + u), (along, h - r - u), (r + u, min(along, h - r)),
                    (w - r - u, min(along, h - r)))[rng.integers(4)]
        if reachable(batch, x, y):
            poses.append((x, y))
    return np.array(poses)


def reachable(batch: RouteBatch, x: float, y: float) -> bool:
    """A centre in the arena (give or take a contact's depth) and outside every box."""
    b, m = batch.static.boxes, batch.radius_m - 0.01
    inside = ((b[:, 0] <= x) & (x <= b[:, 2]) & (b[:, 1] <= y) & (y <= b[:, 3])).any()
    return (not inside and m <= x <= batch.scenario.width_m - m
            and m <= y <= batch.scenario.height_m - m)


@pytest.mark.parametrize("name", ["paper-40", "maze-1", "rooms-1"])
def test_contacts_began_equals_chipmunks_shape_query(name):
    batch = RouteBatch(resolve_scenario(name), 1)
    rng = np.random.default_rng(3)
    out = contact_buffer(1)
    rb = batch.robots[0]
    args = (batch.params, batch.static, batch.scratch)
    touched = ambiguous = 0
    for x, y in near_surface_poses(batch, rng, 3000):
        want = chipmunk_contacts(batch, x, y)
        rb["x"], rb["y"], rb["resting"], rb["forced"] = x, y, False, False
        n = contacts_began(rb, *args, out[0])
        if n < 0:  # left to Chipmunk: only a box within rounding of touching
            ambiguous += 1
            continue
        assert_same(booked(out[0], n), want)
        touched += n > 0
    assert touched > 1000 and ambiguous == 0  # both sides sampled; none within 1e-12


def test_a_resting_robot_books_only_shapes_it_did_not_touch_before_the_step():
    """RouteBatch._check's rule: resting, only shapes it did not touch at (px, py); the
    bumper pressed home (forced), every shape it touches."""
    batch = RouteBatch(resolve_scenario("maze-1"), 1)
    rng = np.random.default_rng(5)
    out = contact_buffer(1)
    rb = batch.robots[0]
    args = (batch.params, batch.static, batch.scratch)
    poses = near_surface_poses(batch, rng, 1500)
    kept = dropped = 0
    for x0, y0 in poses:
        a = rng.uniform(0, 2 * math.pi)  # a step of 1 cm from (x0, y0)
        x1, y1 = x0 + 0.01 * math.cos(a), y0 + 0.01 * math.sin(a)
        if not reachable(batch, x1, y1):
            continue
        before = frozenset(info.shape for info in touching(batch, x0, y0))
        for forced in (False, True):
            want = chipmunk_contacts(batch, x1, y1, frozenset() if forced else before)
            rb["x"], rb["y"], rb["px"], rb["py"] = x1, y1, x0, y0
            rb["resting"], rb["forced"] = True, forced
            n = contacts_began(rb, *args, out[0])
            assert n >= 0
            assert_same(booked(out[0], n), want)
            if not forced:
                kept += n
                dropped += len(chipmunk_contacts(batch, x1, y1)) - n
    assert kept > 20 and dropped > 200  # both kinds of shape were seen


def test_a_box_within_rounding_of_touching_is_left_to_chipmunk():
    batch = RouteBatch(resolve_scenario("maze-1"), 1)
    _, y0, x1, y1 = batch.static.boxes[0]
    rb = batch.robots[0]
    rb["x"], rb["y"] = x1 + batch.radius_m + TOUCH_BAND_M / 2, 0.5 * (y0 + y1)
    rb["resting"] = rb["forced"] = False
    assert contacts_began(rb, batch.params, batch.static, batch.scratch,
                          contact_buffer(1)[0]) == -1
    assert int(CollisionType.CELL) == 4  # the kinds the compiled code writes

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pymunk
import pytest

from sim.physics.reference.controller import PrimitiveController
from sim.physics.reference.world import PhysicsWorld
from sim.physics.static import CollisionType, Contact, PhysicsConfig, merged_boxes
from sim.scenario import Circle, Scenario

ROOM = Scenario(name="room", width_m=8.0, height_m=6.0, start=(1, 1), goal=(6, 4),
                obstacles=(Circle(5.0, 1.5, 0.6),), blocked_cells=((3, 3), (4, 3), (4, 4)))
CFG = PhysicsConfig()


def kinds(world):
    out = {}
    for s in world.space.shapes:
        out[CollisionType(s.collision_type)] = out.get(CollisionType(s.collision_type), 0) + 1
    return out


def test_world_shapes_and_robot():
    w = PhysicsWorld(ROOM, CFG)
    assert kinds(w) == {CollisionType.WALL: 4, CollisionType.OBSTACLE: 1, CollisionType.CELL: 2,
                        CollisionType.ROBOT: 1}
    rb = ROOM.robot
    assert w.robot.mass == rb.mass_kg
    assert w.robot.moment == pytest.approx(0.5 * rb.mass_kg * rb.radius_m**2)
    assert w.pose == (1.5, 1.5, 0.0) and w.steps == 0 and w.time_s == 0.0
    assert w.space.gravity == (0.0, 0.0) and w.space.damping == 1.0
    assert w.pivot.max_bias == 0.0 and w.gear.max_bias == 0.0
    assert w.pivot.max_force == pytest.approx(CFG.traction_margin * rb.mass_kg
                                              * rb.max_wheel_accel_m_s2)


def test_merged_boxes():
    assert merged_boxes(((0, 0), (1, 0), (3, 0), (1, 1), (2, 1))) == [(0, 0, 1), (0, 3, 3),
                                                                      (1, 1, 2)]
    assert merged_boxes(()) == []


def test_config_validation():
    for bad in (dict(dt_s=0.0), dict(substeps=0), dict(iterations=0), dict(tolerance_m=-1.0),
                dict(collision_bias=2.0), dict(timeout_s=math.inf)):
        with pytest.raises(ValueError, match="PhysicsConfig"):
            PhysicsWorld(ROOM, dataclasses.replace(CFG, **bad))


def test_wall_bump_is_a_real_contact_with_points():
    w = PhysicsWorld(ROOM, CFG)
    res = PrimitiveController(ROOM, CFG).run(w, 1)  # down from (1.5, 1.5) -> (1.5, 0.5) is free
    assert res.reached
    res = PrimitiveController(ROOM, CFG).run(w, 1)  # out of the arena
    assert res.bumped and not res.reached and res.state == 1  # placed back on (1, 0)
    assert res.contacts == 1
    (c,) = w.contacts
    assert isinstance(c, Contact) and c.kind is CollisionType.WALL
    assert c.y_m == pytest.approx(-CFG.contact_depth_m) and c.x_m == pytest.approx(1.5)
    assert (c.normal_x, c.normal_y) == pytest.approx((0.0, -1.0))
    assert 0.0 < c.depth_m <= CFG.contact_depth_m + 1e-12
    assert w.contact_counts[CollisionType.WALL] == 1
    assert w.pose == (1.5, 0.5, w.pose[2]) and w.velocity == (0.0, 0.0, 0.0)
    # the deepest point of the bump: the disc entered the wall by contact_depth_m, no more
    ys = np.array(w.trajectory)[:, 1]
    assert ys.min() == pytest.approx(ROOM.robot.radius_m - CFG.contact_depth_m)


def test_obstacle_and_cell_contacts_are_typed():
    ctl = PrimitiveController(ROOM, CFG)
    w = PhysicsWorld(ROOM, CFG, (4.5, 1.5, 0.0))  # inside the circle at (5.0, 1.5)
    assert w.overlap_m() > 0  # a pose that overlaps is allowed but reported
    w = PhysicsWorld(ROOM, CFG, (3.5, 1.5, 0.0))
    res = ctl.run(w, 3)  # right, into the circle
    assert res.bumped and w.contacts[0].kind is CollisionType.OBSTACLE
    w = PhysicsWorld(ROOM, CFG, (3.5, 2.5, 0.0))
    res = ctl.run(w, 0)  # up, into blocked cell (3, 3)
    assert res.bumped and w.contacts[0].kind is CollisionType.CELL
    assert w.overlap_m() == 0.0


def test_placement_leaves_the_robot_still():
    w = PhysicsWorld(ROOM, CFG, (3.5, 2.5, 0.0))
    ctl = PrimitiveController(ROOM, CFG)
    for _ in range(3):
        assert ctl.run(w, 0).bumped
        assert w.pose[:2] == (3.5, 2.5)
    traj: list = []
    w.drive([(0.0, 0.0, 0.0)] * 3, None, traj)
    assert all(p[:2] == (3.5, 2.5) for p in traj)  # no leftover correction velocity


def test_cast_sees_shapes_off_the_centre_line():
    # Chipmunk2D#138: the spatial index ignores the query radius, so a circle whose
    # bounding box the centre line misses is not found by space.segment_query_first
    sc = Scenario(name="graze", width_m=6.0, height_m=6.0, start=(0, 0), goal=(5, 5),
                  obstacles=(Circle(3.0, 2.05, 1.2),))
    w = PhysicsWorld(sc, CFG)
    a, b = (0.5, 3.5), (5.5, 3.5)  # the disc (r=0.3) grazes the circle's top (y = 3.25)
    r = sc.robot.radius_m
    assert w.space.segment_query_first(a, b, r, pymunk.ShapeFilter(mask=0b10)) is None
    alpha = w.cast_alpha(*a, *b)
    assert alpha is not None and 0.3 < alpha < 0.6
    guard = w.cast_free_distance(*a, *b, 5.0)
    assert guard is not None and guard[4] == pytest.approx(alpha * 5.0 + CFG.contact_depth_m)
    assert w.cast_free_distance(0.5, 0.5, 5.5, 0.5, 5.0) is None


def run_actions(sc, actions, cfg=CFG, public=False):
    w = PhysicsWorld(sc, cfg)
    if public:
        w.use_public_api()
    ctl = PrimitiveController(sc, cfg)
    out = []
    for a in actions:
        n0 = len(w.contacts)
        res = ctl.run(w, a)
        out.append((res.state, res.bumped, tuple(w.trajectory), tuple(w.contacts[n0:])))
    return out


def test_fresh_world_replays_bit_for_bit_and_public_api_agrees():
    actions = np.random.default_rng(5).integers(4, size=150).tolist()
    first = run_actions(ROOM, actions)
    assert first == run_actions(ROOM, actions)
    assert first == run_actions(ROOM, actions, public=True)
    assert any(bumped for _, bumped, _, _ in first)


def test_advance_guards_free_driving():
    cfg = PhysicsConfig(dt_s=0.05, substeps=2)
    w = PhysicsWorld(ROOM, cfg, (1.5, 1.5, 0.0))
    w.set_twist(-3.0, 0.0, 0.0)  # far faster than the wheels allow: 15 cm per step
    traj: list = []
    n = w.advance(20, traj)
    xs = np.array(traj)[:, 0]
    assert n >= 1 and w.contacts[0].kind is CollisionType.WALL
    assert xs.min() >= ROOM.robot.radius_m - cfg.contact_depth_m - 1e-9


def test_respawn_replays_like_a_fresh_world():
    """A reset keeps the static shapes and puts a new robot in: every primitive (state, bump,
    pose, steps, contacts) equals what a fresh world gives, after earlier episodes too."""
    import numpy as np

    from scenarios.runs.spec import load
    from sim.grid.discretiser import Discretiser

    sc, m = load("paper-50")
    cfg = PhysicsConfig()
    ctl, disc = PrimitiveController(sc, cfg), Discretiser.from_scenario(sc)
    rng = np.random.default_rng(0)
    starts = [int(s) for s in rng.choice(m.start_states, 6)]
    actions = [[int(a) for a in rng.integers(0, 4, 30)] for _ in starts]

    def episodes(respawn: bool) -> list:
        out, world = [], None
        for s, acts in zip(starts, actions, strict=True):
            pose = (*disc.state_centre(s), 0.0)
            if respawn and world is not None:
                world.respawn(pose)
            else:
                world = PhysicsWorld(sc, cfg, pose)
            out.append([(r.state, r.bumped, world.pose, world.steps, len(world.contacts))
                        for r in (ctl.run(world, a) for a in acts)])
        return out

    fresh = episodes(respawn=False)
    assert sum(b for ep in fresh for _, b, *_ in ep) > 5  # bumps happen: contacts tested too
    assert episodes(respawn=True) == fresh

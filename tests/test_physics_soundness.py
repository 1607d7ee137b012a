"""Physical soundness of the primitive world, measured against exact geometry.

The oracle (:func:`signed_clearance`) is written here from the scenario alone,
independent of Pymunk and of :mod:`sim.physics`, so the simulator is checked
against geometry it does not compute itself.
"""

from __future__ import annotations

import numpy as np
import pytest

from sim.grid import build_model
from sim.grid.planning import bfs_route
from sim.physics.envs.diffdrive import DIFFDRIVE_CONFIG, DiffDriveEnv
from sim.physics.envs.route import PhysicsRouteEnv
from sim.physics.reference.world import PhysicsConfig, PhysicsWorld
from sim.scenario import Scenario
from sim.scenario_io import builtin_names, resolve_scenario

MAX_OVERLAP_M = 0.01


def signed_clearance(sc: Scenario, xy: np.ndarray) -> np.ndarray:
    """Gap between the robot's disc at each point and the nearest static surface [m]."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    x, y = xy[:, 0], xy[:, 1]
    gap = np.minimum.reduce([x, y, sc.width_m - x, sc.height_m - y])
    if sc.obstacles:
        circ = np.array([(o.x_m, o.y_m, o.radius_m) for o in sc.obstacles])
        d = np.hypot(x[:, None] - circ[None, :, 0], y[:, None] - circ[None, :, 1])
        gap = np.minimum(gap, (d - circ[None, :, 2]).min(axis=1))
    c = sc.cell_size_m
    if sc.blocked_cells:  # squares within reach of a disc (radius < cell) are the 3x3 around it
        blocked = np.zeros((sc.ny + 2, sc.nx + 2), dtype=bool)  # one-cell border of free
        for ix, iy in sc.blocked_cells:
            blocked[iy + 1, ix + 1] = True
        cx = np.clip(np.floor(x / c).astype(int), 0, sc.nx - 1)
        cy = np.clip(np.floor(y / c).astype(int), 0, sc.ny - 1)
        for oy in (-1, 0, 1):
            for ox in (-1, 0, 1):
                ix, iy = cx + ox, cy + oy
                hit = blocked[iy + 1, ix + 1]
                dx = np.maximum(np.abs(x - (ix + 0.5) * c) - c / 2, 0.0)
                dy = np.maximum(np.abs(y - (iy + 0.5) * c) - c / 2, 0.0)
                depth = np.minimum(c / 2 - np.abs(x - (ix + 0.5) * c),
                                   c / 2 - np.abs(y - (iy + 0.5) * c))
                d = np.where((dx == 0) & (dy == 0), -depth, np.hypot(dx, dy))
                gap = np.where(hit, np.minimum(gap, d), gap)
    return gap - sc.robot.radius_m


def test_oracle_on_known_points():
    sc = Scenario(name="o", width_m=4.0, height_m=4.0, start=(0, 0), goal=(3, 3),
                  blocked_cells=((2, 2),))
    from sim.scenario import Circle
    sc2 = Scenario(name="o2", width_m=4.0, height_m=4.0, start=(0, 0), goal=(3, 3),
                   obstacles=(Circle(1.0, 3.0, 0.5),))
    r = sc.robot.radius_m
    got = signed_clearance(sc, [(0.5, 0.5), (1.5, 2.5), (2.5, 2.5), (0.2, 1.0)])
    assert got == pytest.approx([0.5 - r, 0.5 - r, -0.5 - r, 0.2 - r])
    assert signed_clearance(sc2, [(1.0, 2.0)])[0] == pytest.approx(0.5 - r)


def explore(sc: Scenario, n: int, seed: int, episode: int = 200):
    """Random primitives from random start cells; returns per-primitive records."""
    env = PhysicsRouteEnv(sc)
    rng = np.random.default_rng(seed)
    s, _ = env.reset(seed=seed, options={"start": "random"})
    rows, trajs = [], []
    for i in range(n):
        if i and i % episode == 0:
            s, _ = env.reset(options={"start": "random"})
        a = int(rng.integers(4))
        s2, _, term, _, info = env.step(a)
        trajs.append(env.trajectory()[:, :2])
        rows.append((s, a, s2, info["bumped"]))
        s = s2
        if term:
            s, _ = env.reset(options={"start": "random"})
    worst = float(signed_clearance(sc, np.concatenate(trajs)).min())
    return np.array(rows, dtype=np.int64), worst


def check_sound_and_agreeing(sc: Scenario, n: int, seed: int) -> tuple[float, float]:
    rows, worst = explore(sc, n, seed)
    assert worst >= -MAX_OVERLAP_M, f"overlap {-worst:.4f} m"
    assert worst >= -(PhysicsConfig().contact_depth_m + 1e-9)  # and in fact never deeper
    m = build_model(sc)
    s, a, s2 = rows[:, 0], rows[:, 1], rows[:, 2]
    expected = m.next_state[s, a]
    free = expected != s
    agree_all = float((s2 == expected).mean())
    agree_free = float((s2[free] == expected[free]).mean())
    assert agree_free >= 0.999, agree_free
    assert rows[:, 3].sum() > 0  # the exploration did bump into things
    return agree_all, agree_free


def test_random_primitives_are_sound_paper50(paper50):
    agree_all, _ = check_sound_and_agreeing(paper50, 3000, seed=1)
    assert agree_all >= 0.98


@pytest.mark.slow
def test_100k_random_primitives_are_sound_paper50(paper50):
    agree_all, agree_free = check_sound_and_agreeing(paper50, 100_000, seed=2)
    print(f"\nagreement with the grid model: all {agree_all:.5f}, free moves {agree_free:.5f}")


@pytest.mark.parametrize("name", builtin_names())
def test_bfs_route_drives_without_contact(name):
    sc = resolve_scenario(name)
    m = build_model(sc)
    route = bfs_route(m.next_state, m.distance_to_goal, m.start)
    assert len(route) == m.optimal_route_length + 1
    env = PhysicsRouteEnv(sc)
    s, _ = env.reset(seed=0)
    for nxt in route[1:]:
        a = next(a for a in range(4) if m.next_state[s, a] == nxt)
        s, _r, term, _, info = env.step(a)
        assert s == nxt and not info["contacts"]
        assert signed_clearance(sc, env.trajectory()[:, :2]).min() > 0
    assert term and env.world.contacts == [] and env.world.steps > 0


def test_arena_map_cells_are_sound():
    sc = resolve_scenario("arena")
    agree_all, _ = check_sound_and_agreeing(sc, 1500, seed=3)
    assert agree_all >= 0.98


def test_world_never_overlaps_when_started_free(paper50):
    w = PhysicsWorld(paper50)
    assert w.overlap_m() == 0.0


def test_diffdrive_random_driving_is_sound(paper50):
    env = DiffDriveEnv(paper50)
    env.reset(seed=4, options={"start": "random"})
    env.action_space.seed(4)
    rng = np.random.default_rng(4)
    trajs, contacts = [], 0
    action = env.action_space.sample()
    for i in range(1500):
        if i % 15 == 0:  # hold an action for a while; often full speed ahead
            action = (np.ones(2, dtype=np.float32) if rng.random() < 0.5
                      else env.action_space.sample())
        _, _, term, _, info = env.step(action)
        trajs.append(env.trajectory()[:, :2])
        contacts += info["contacts"]
        if term or i % 300 == 299:
            env.reset(options={"start": "random"})
    gap = signed_clearance(paper50, np.concatenate(trajs))
    assert contacts > 0
    assert gap.min() >= -(DIFFDRIVE_CONFIG.contact_depth_m + 1e-9) >= -MAX_OVERLAP_M

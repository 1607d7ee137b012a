"""The Gymnasium ``rgb_array`` render (sim/render.py), the other way to watch a run: the
robot is a disc of its real radius, large enough to see, with its heading drawn in it."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import sim  # noqa: F401  (registers the ids)
from sim.render import AGENT, MAX_SIDE_PX, ROBOT_PX, default_px_per_m
from sim.scenario_io import resolve_scenario


def robot_pixels(img: np.ndarray) -> np.ndarray:
    """(row, col) of the robot's fill and its darker rim."""
    fill = np.all(img == AGENT, axis=2)
    rim = np.all(img == tuple(int(0.55 * v) for v in AGENT), axis=2)
    return np.argwhere(fill | rim)


def test_the_scale_gives_the_robot_a_visible_disc(paper50):
    px = default_px_per_m(paper50)
    assert paper50.robot.radius_m * px == pytest.approx(ROBOT_PX)
    assert max(paper50.width_m, paper50.height_m) * px <= MAX_SIDE_PX
    small = resolve_scenario("maze-1")  # a small arena: at least the old 400 pixels
    assert max(small.width_m, small.height_m) * default_px_per_m(small) >= 400


@pytest.mark.parametrize("turns", [0, 1])
def test_physics_render_draws_the_robot_to_scale_with_its_heading(turns):
    env = gym.make("rnhql/PhysicsRoute-v0", render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(turns):
        env.step(0)  # a move up turns the robot to face +y first
    base = env.unwrapped
    img = env.render()
    x, y, heading = base.world.pose
    px = base._trail.canvas.px_per_m
    pts = robot_pixels(img)
    r = base.scenario.robot.radius_m * px
    assert r >= 5.0  # a body, not a dot
    assert len(pts) == pytest.approx(math.pi * r * r, rel=0.35)  # its real radius
    centre = pts.mean(axis=0)  # (row, col)
    row0, col0 = base._trail.canvas.to_pixel(x, y)
    assert np.hypot(centre[0] - row0, centre[1] - col0) <= 2.0
    # the heading: white pixels inside the disc, on the side the robot faces
    box = img[row0 - round(r):row0 + round(r) + 1, col0 - round(r):col0 + round(r) + 1]
    white = np.argwhere(np.all(box == 255, axis=2)) - round(r)
    assert len(white) >= 3
    facing = np.array([-math.sin(heading), math.cos(heading)])  # (row, col): rows grow down
    assert white.mean(axis=0) @ facing > 1.0
    env.close()


def test_grid_render_draws_the_robot_disc_to_scale():
    env = gym.make("rnhql/GridRoute-v0", render_mode="rgb_array")
    env.reset(seed=0)
    img = env.render()
    base = env.unwrapped
    r = base.scenario.robot.radius_m * default_px_per_m(base.scenario)
    assert len(robot_pixels(img)) == pytest.approx(math.pi * r * r, rel=0.35)
    env.close()

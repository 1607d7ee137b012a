"""What both physics envs share: the ``pose`` of their info dicts and the ``rgb_array``
picture (the map, the trail of substep positions, the contacts, the robot and its heading).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from sim.physics.motion import wrap_angle
from sim.render import AGENT, PATH, MapCanvas
from sim.scenario import Scenario

CONTACT = (240, 140, 0)


def info_pose(x: float, y: float, th: float) -> np.ndarray:
    """An info ``pose``: float64[3] (x [m], y [m], heading [rad] in [-pi, pi))."""
    return np.array((x, y, wrap_angle(th)))


class Trail:
    """Render helper: the map, a trail of substep positions, the robot and its heading."""

    def __init__(self, sc: Scenario, blocked: np.ndarray) -> None:
        self.canvas = MapCanvas(sc, blocked)
        self.sc = sc
        self.chunks: list[np.ndarray] = []

    def draw(self, pose: tuple[float, float, float], contacts: list[Any]) -> np.ndarray:
        cv = self.canvas
        img = cv.background.copy()
        if self.chunks:
            pts = np.concatenate(self.chunks)[:, :2]
            cols = np.clip((pts[:, 0] * cv.px_per_m).astype(int), 0, cv.w - 1)
            rows = np.clip(((self.sc.height_m - pts[:, 1]) * cv.px_per_m).astype(int), 0,
                           cv.h - 1)
            img[rows, cols] = PATH
        for c in contacts[-50:]:
            cv.disc(img, c.x_m, c.y_m, 0.6 / cv.px_per_m, CONTACT)
        x, y, th = pose
        r = max(self.sc.robot.radius_m, 3.0 / cv.px_per_m)  # visible at any scale
        cv.disc(img, x, y, r, AGENT)
        cv.polyline(img, np.array([[x, y], [x + r * math.cos(th), y + r * math.sin(th)]]),
                    (255, 255, 255))
        return img

"""Numpy drawing of a scenario for ``render_mode="rgb_array"`` (no pygame needed).

Image row 0 is the top of the arena (y up in the world, rows down in the image).

The scale is chosen for the robot: everything is drawn to scale, so at a fixed 400
pixels for a 50 m arena the 0.3 m robot was a dot of two pixels and its heading
invisible. :func:`default_px_per_m` makes the robot's disc ``ROBOT_PX`` pixels in
radius where the image can stay within ``MAX_SIDE_PX`` (paper-50: 20 px/m, 1000
pixels a side).
"""

from __future__ import annotations

import numpy as np

from sim.scenario import Scenario

FREE = (250, 250, 250)
INFLATED = (225, 225, 232)  # cells blocked only for the inflated robot
OBSTACLE = (70, 74, 84)
START = (46, 160, 67)
GOAL = (230, 170, 20)
PATH = (60, 120, 230)
AGENT = (220, 50, 50)


ROBOT_PX = 6.0  # the robot's radius in pixels, where MAX_SIDE_PX allows
MIN_SIDE_PX, MAX_SIDE_PX = 400, 1024  # the image's longer side, at least / at most


def default_px_per_m(sc: Scenario) -> float:
    """Pixels per metre: the robot ``ROBOT_PX`` pixels in radius, the longer side between
    ``MIN_SIDE_PX`` and ``MAX_SIDE_PX`` (a very large arena falls back to 4 px/m)."""
    longest = max(sc.width_m, sc.height_m)
    want = max(ROBOT_PX / sc.robot.radius_m, MIN_SIDE_PX / longest)
    return max(4.0, min(want, MAX_SIDE_PX / longest))


class MapCanvas:
    """A pre-rendered background plus helpers to draw cells and points on a copy."""

    def __init__(self, sc: Scenario, blocked: np.ndarray, px_per_m: float | None = None) -> None:
        self.sc = sc
        self.px_per_m = px_per_m or default_px_per_m(sc)
        self.w = round(sc.width_m * self.px_per_m)
        self.h = round(sc.height_m * self.px_per_m)
        img = np.empty((self.h, self.w, 3), dtype=np.uint8)
        img[:] = FREE
        # inflated occupancy, cell by cell
        xs, ys = self._pixel_world()
        c = sc.cell_size_m
        ix = np.clip((xs / c).astype(int), 0, sc.nx - 1)
        iy = np.clip((ys / c).astype(int), 0, sc.ny - 1)
        img[blocked[iy, ix]] = INFLATED
        cells = np.zeros((sc.ny, sc.nx), dtype=bool)  # a map's blocked cells (.map files)
        for ox, oy in sc.blocked_cells:
            cells[oy, ox] = True
        solid = cells[iy, ix]
        for o in sc.obstacles:
            solid |= (xs - o.x_m) ** 2 + (ys - o.y_m) ** 2 <= o.radius_m**2
        img[solid] = OBSTACLE
        self.background = img
        for cell, colour in ((sc.start, START), (sc.goal, GOAL)):
            self.fill_cell(self.background, cell, colour)

    def _pixel_world(self) -> tuple[np.ndarray, np.ndarray]:
        cols = (np.arange(self.w) + 0.5) / self.px_per_m
        rows = self.sc.height_m - (np.arange(self.h) + 0.5) / self.px_per_m
        return np.meshgrid(cols, rows)

    def to_pixel(self, x_m: float, y_m: float) -> tuple[int, int]:
        """World point -> (row, col), clipped into the image."""
        col = int(np.clip(x_m * self.px_per_m, 0, self.w - 1))
        row = int(np.clip((self.sc.height_m - y_m) * self.px_per_m, 0, self.h - 1))
        return row, col

    def fill_cell(self, img: np.ndarray, cell: tuple[int, int], colour: tuple[int, int, int],
                  shrink: float = 0.2) -> None:
        c = self.sc.cell_size_m
        ix, iy = cell
        r0, c0 = self.to_pixel((ix + shrink) * c, (iy + 1 - shrink) * c)
        r1, c1 = self.to_pixel((ix + 1 - shrink) * c, (iy + shrink) * c)
        img[r0:r1 + 1, c0:c1 + 1] = colour

    def disc(self, img: np.ndarray, x_m: float, y_m: float, radius_m: float,
             colour: tuple[int, int, int]) -> None:
        """A filled disc; one of 4 pixels or more in radius (the robot) gets a darker rim,
        so it reads as a body and not a blot."""
        r = max(1, round(radius_m * self.px_per_m))
        row, col = self.to_pixel(x_m, y_m)
        rr, cc = np.ogrid[-r:r + 1, -r:r + 1]
        d2 = rr**2 + cc**2
        mask = d2 <= r * r
        r0, c0 = row - r, col - r
        sub = img[max(r0, 0):row + r + 1, max(c0, 0):col + r + 1]
        win = (slice(max(-r0, 0), max(-r0, 0) + sub.shape[0]),
               slice(max(-c0, 0), max(-c0, 0) + sub.shape[1]))
        sub[mask[win]] = colour
        if r >= 4:
            rim = mask & (d2 > (r - 1.5) ** 2)
            sub[rim[win]] = tuple(int(0.55 * v) for v in colour)

    def polyline(self, img: np.ndarray, points_m: np.ndarray,
                 colour: tuple[int, int, int]) -> None:
        """Draw a trail by dense sampling of each segment (adequate at these sizes)."""
        pts = np.asarray(points_m, dtype=float)
        if len(pts) == 0:
            return
        if len(pts) == 1:
            pts = np.vstack([pts, pts])
        seg = np.diff(pts, axis=0)
        lengths = np.hypot(seg[:, 0], seg[:, 1])
        for p, d, n in zip(pts[:-1], seg, np.ceil(lengths * self.px_per_m * 2).astype(int) + 1,
                           strict=True):
            t = np.linspace(0.0, 1.0, n)[:, None]
            q = p + t * d
            cols = np.clip((q[:, 0] * self.px_per_m).astype(int), 0, self.w - 1)
            rows = np.clip(((self.sc.height_m - q[:, 1]) * self.px_per_m).astype(int), 0,
                           self.h - 1)
            img[rows, cols] = colour

"""Pose <-> cell, cell centres and the robot-inflated occupancy grid.

Frames (see :mod:`sim.scenario`): metres, x right, y up, origin bottom-left.
Cell ``(ix, iy)`` covers ``[ix*c, (ix+1)*c) x [iy*c, (iy+1)*c)``: a pose exactly
on a border belongs to the cell above/right of it (``floor``), and poses on the
far walls (x == width or y == height) are clamped into the last cell, so every
pose inside the closed arena maps to exactly one cell. The state index of a
cell is ``s = iy * nx + ix``, so ``sim.grid.raster.occupancy(...).ravel()[s]`` is that state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sim.scenario import Scenario


@dataclass(frozen=True)
class Discretiser:
    nx: int  # cells along x
    ny: int  # cells along y
    cell_size_m: float  # [m]

    @classmethod
    def from_scenario(cls, sc: Scenario) -> Discretiser:
        return cls(sc.nx, sc.ny, sc.cell_size_m)

    @property
    def n_states(self) -> int:
        return self.nx * self.ny

    # ---- pose -> cell
    def cell_of(self, x_m: float, y_m: float) -> tuple[int, int]:
        """The cell holding the point; clamped into the arena."""
        ix = min(max(math.floor(x_m / self.cell_size_m), 0), self.nx - 1)
        iy = min(max(math.floor(y_m / self.cell_size_m), 0), self.ny - 1)
        return int(ix), int(iy)

    def state_of(self, x_m: float, y_m: float) -> int:
        ix, iy = self.cell_of(x_m, y_m)
        return iy * self.nx + ix

    def state_of_pose(self, pose: tuple[float, float, float]) -> int:
        """A pose (x [m], y [m], heading [rad]) -> state; heading does not matter."""
        return self.state_of(pose[0], pose[1])

    # ---- cell -> pose
    def index(self, ix: int, iy: int) -> int:
        return iy * self.nx + ix

    def cell(self, state: int) -> tuple[int, int]:
        return state % self.nx, state // self.nx

    def cell_centre(self, ix: int, iy: int) -> tuple[float, float]:
        c = self.cell_size_m
        return (ix + 0.5) * c, (iy + 0.5) * c

    def state_centre(self, state: int) -> tuple[float, float]:
        return self.cell_centre(*self.cell(state))

    def pose_of_state(self, state: int, heading_rad: float = 0.0) -> tuple[float, float, float]:
        x, y = self.state_centre(state)
        return x, y, heading_rad

    def centres(self) -> np.ndarray:
        """float64[n_states, 2]: every cell centre in state order [m]."""
        iy, ix = np.divmod(np.arange(self.n_states), self.nx)
        return np.stack([(ix + 0.5) * self.cell_size_m, (iy + 0.5) * self.cell_size_m], axis=1)

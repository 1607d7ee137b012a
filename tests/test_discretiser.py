from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from sim.grid.discretiser import Discretiser
from sim.grid.raster import occupancy
from sim.scenario import Circle, Scenario

sizes = st.tuples(st.integers(2, 60), st.integers(2, 60),
                  st.sampled_from([0.25, 0.5, 1.0, 2.0]))


@given(sizes, st.data())
def test_centre_of_a_cell_maps_back_to_it(size, data):
    nx, ny, c = size
    d = Discretiser(nx, ny, c)
    ix, iy = data.draw(st.integers(0, nx - 1)), data.draw(st.integers(0, ny - 1))
    assert d.cell_of(*d.cell_centre(ix, iy)) == (ix, iy)
    s = d.index(ix, iy)
    assert d.cell(s) == (ix, iy)
    assert d.state_of_pose(d.pose_of_state(s, 1.0)) == s


@given(sizes, st.floats(0, 1), st.floats(0, 1), st.floats(-math.pi, math.pi))
def test_every_pose_in_the_arena_maps_to_a_cell_in_range(size, fx, fy, heading):
    nx, ny, c = size
    d = Discretiser(nx, ny, c)
    x, y = fx * nx * c, fy * ny * c  # includes the far walls (fx = 1)
    s = d.state_of_pose((x, y, heading))
    assert 0 <= s < nx * ny
    ix, iy = d.cell(s)
    # the point lies in the (closed) square of its cell
    assert ix * c <= x <= (ix + 1) * c and iy * c <= y <= (iy + 1) * c


@given(sizes, st.data())
def test_poses_on_borders_map_deterministically_up_and_right(size, data):
    nx, ny, c = size
    d = Discretiser(nx, ny, c)
    ix, iy = data.draw(st.integers(1, nx - 1)), data.draw(st.integers(1, ny - 1))
    # an exact interior border belongs to the cell above/right of it, every time
    x, y = ix * c, iy * c
    assert d.cell_of(x, y) == d.cell_of(x, y) == (ix, iy)


def test_occupancy_inflates_obstacles_by_radius_plus_clearance():
    sc = Scenario(name="t", width_m=10, height_m=10, start=(0, 0), goal=(9, 9),
                  obstacles=(Circle(5.0, 5.0, 1.0),))
    blocked = occupancy(sc)
    infl = sc.robot.inflation_m
    xy = Discretiser.from_scenario(sc).centres()
    expected = np.hypot(xy[:, 0] - 5.0, xy[:, 1] - 5.0) < 1.0 + infl
    assert (blocked.ravel() == expected).all()
    assert blocked[4, 4] and not blocked[0, 0]

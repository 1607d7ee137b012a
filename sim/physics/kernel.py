"""Motion primitives for many robots at once, in compiled code: Chipmunk's own integration
where nothing can touch, Chipmunk itself (through :mod:`sim.physics.batch`) where something might.

Why this is the physics of the reference world (:class:`sim.physics.world.PhysicsWorld`
driven by :class:`sim.physics.controller.PrimitiveController`). The robot is pulled by a
kinematic control body through a pivot and a gear joint with ``max_bias = 0`` (see
:mod:`sim.physics.world`). Away from contacts Chipmunk's step does, per robot:

1. ``p += v * dt``, ``theta += omega * dt`` (position integrates first, with the velocity
   the last solve left; ``v_bias = 0`` because ``collision_bias = 1``);
2. collision detection (nothing overlaps: no arbiter);
3. velocity solve: the joints drive ``(v, omega)`` to the control body's twist exactly (to
   rounding: the joint's effective mass is the robot's own), or by their impulse limit
   (``max_force * dt``, the wheels' traction) when noise or a guard-shortened step asks
   for more.

:func:`advance` performs 1 and 3 in float64 in the same order. Step 2 matters only where
the disc may touch something: at ``exact`` where the leg's swept-disc guard (cast with
Chipmunk's segment-query formulas, :mod:`sim.physics.sweep`; cached per (cell, action) for
legs from a cell centre) says the step ends at its surface; above ``exact`` where the disc
ends within 1 um of a shape it did not overlap before the step. Such a step is handed back
(``CHECK``) and the caller asks Chipmunk's narrow phase (``cpSpaceShapeQuery``) whether a
contact began. The controller is the controller module's compiled functions
(:func:`sim.physics.controller.plan_leg`, ``leg_command``, ``wheel_twist``, ``at_target``,
``cell_of``); the fidelity knobs follow the reference's rules (:meth:`PrimitiveController.run`),
tested field by field at ``exact``, wheel noise only and ``noisy``.

State by name: each robot is a record of :data:`ROBOT` (``robots["x"]``: every robot's x;
in compiled code ``rb = robots[i]``, a reference: ``rb.x``); a batch's constants are one
:class:`Params`, its caches one :class:`Scratch`. Not a NamedTuple of arrays: numba types a
NamedTuple argument by its slow path on every call (10-14 us for fifty arrays, measured; a
record array 0.4 us), and a batch of one makes a call per primitive (~28 us). Params and
Scratch cross as plain tuples for the same reason, rebuilt inside (``Params(*pt)``).
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit

from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS
from sim.physics.controller import (
    Leg,
    Profiles,
    at_target,
    cell_of,
    leg_command,
    plan_leg,
    wheel_twist,
)
from sim.physics.static import DEEPER_M, HOLD_STEP_M
from sim.physics.sweep import _box_distance, _segment_distance, overlap_depth, sweep_fraction


class Status(IntEnum):
    """Where a robot's primitive stands between calls of :func:`advance`."""

    IDLE, RUNNING = 0, 1  # no primitive (placed, never stepped); running
    NOISE = 2  # the caller refills the robot's normals, then calls again
    CHECK = 3  # the caller asks Chipmunk whether the last step began a contact
    CONTACT = 4  # the caller found one (and booked it): the primitive ends in a bump
    DONE = 5


class Phase(IntEnum):
    """Where a robot stands within its current leg: plan it from the pose, cast its guard,
    drive its commands."""

    PLAN, GUARD, DRIVE = 0, 1, 2


_F, _I, _B = np.float64, np.int64, np.bool_
ROBOT = np.dtype([
    # pose [m, m, rad] (heading not wrapped), velocity after the last solve, control twist
    ("x", _F), ("y", _F), ("th", _F), ("vx", _F), ("vy", _F), ("w", _F),
    ("cvx", _F), ("cvy", _F), ("cw", _F),
    ("px", _F), ("py", _F), ("pth", _F),  # pose before the last step
    # the primitive: action, start cell, target centre [m] and heading [rad]
    ("action", _I), ("cell_x", _I), ("cell_y", _I), ("tx", _F), ("ty", _F), ("head", _F),
    ("status", _I), ("state", _I),  # Status; the cell of the final pose (when DONE)
    ("steps", _I), ("steps0", _I),  # physics steps since placed; at the primitive's start
    ("bumped", _B), ("reached", _B), ("timeout", _B), ("ncontact", _I),
    ("resting", _B), ("press", _F),  # at rest against a surface (_held); bumper travel [m]
    ("forced", _B), ("ntraj", _I),  # the last step pressed the bumper home; poses recorded
    ("phase", _I),  # the leg (a sim.physics.controller.Leg), where it stands, its guard:
    ("nturn", _I), ("tsign", _F), ("tscale", _F), ("ndrive", _I), ("dscale", _F), ("ex", _F),
    ("ey", _F), ("dist", _F),
    ("cmd", _I), ("sub", _I), ("cmd_set", _I),  # command and substep now; command in cv*
    ("gx", _F), ("gy", _F), ("limit", _F), ("free", _F),  # leg guard: start, allowance, free
], align=True)

CHECK_MARGIN_M = 1e-6  # steps ending this close to a surface ask Chipmunk [m]
CENTRE_TOL_M = 1e-9  # a leg starting this close to its cell centre uses the cached guard [m]
_DELTAS = np.array(ACTION_DELTAS, dtype=np.int64)
_HEADINGS = np.array(ACTION_HEADINGS, dtype=np.float64)


class Params(NamedTuple):
    """A batch's constants (scenario, :class:`PhysicsConfig`, fidelity, static geometry)."""

    dt: float  # physics step [s]
    substeps: int  # physics steps per control period (of `period` [s])
    period: float
    tol_m: float  # a primitive ends this close to the target centre [m]
    tol_rad: float  # ... and to its heading [rad]
    timeout_steps: int  # a primitive gives up after this many steps (checked between legs)
    depth_m: float  # deepest a guarded step carries the disc into a surface [m]
    dv_max: float  # the pivot joint's impulse limit per step, as a speed change [m/s]
    dw_max: float  # the gear joint's, as a yaw-rate change [rad/s]
    cell_m: float  # cell size [m]
    nx: int  # grid width [cells]
    ny: int  # grid height [cells]
    radius_m: float  # robot radius [m]
    wheel_base_m: float  # [m]
    wheel_noise: float  # fidelity: relative sigma of each wheel's speed per period [-]
    carried: bool  # fidelity: carried pose
    bumper_travel_m: float  # fidelity: bumper travel [m]
    turn_caps: np.ndarray  # the profile tables (sim.physics.controller.Profiles)
    turn_sums: np.ndarray
    drive_caps: np.ndarray
    drive_sums: np.ndarray
    circles: np.ndarray  # static geometry (sim.physics.sweep.StaticGeometry)
    walls: np.ndarray
    boxes: np.ndarray
    grid_start: np.ndarray
    grid_items: np.ndarray


class Scratch(NamedTuple):
    """A batch's mutable helpers in compiled code."""

    guards: np.ndarray  # float64[cells, 4]: free distance of each (cell, action)'s drive leg
    #   from the cell centre (inf: nothing in the way; nan: not cast yet); shareable
    seen: np.ndarray  # int64[circles + boxes]: candidate stamps of the sweep
    counters: np.ndarray  # int64[2]: the sweep's stamp, guard casts so far


@njit(cache=True)
def begin_all(robots, actions, active, cell_m, nx, ny):
    """Start grid ``actions[i]`` for every ``active`` robot from its pose (its cell as the
    discretiser says, clamped into the grid)."""
    for i in range(robots.shape[0]):
        if not active[i]:
            continue
        rb, a = robots[i], actions[i]
        rb.cell_x, rb.cell_y = cell_of(rb.x, rb.y, cell_m, nx, ny)
        rb.action = a
        rb.tx = (rb.cell_x + _DELTAS[a, 0] + 0.5) * cell_m
        rb.ty = (rb.cell_y + _DELTAS[a, 1] + 0.5) * cell_m
        rb.head = _HEADINGS[a]
        rb.steps0 = rb.steps
        rb.bumped = rb.reached = rb.timeout = rb.forced = False
        rb.ncontact = 0
        rb.press = 0.0
        rb.phase = Phase.PLAN
        rb.cmd_set = -1
        rb.ntraj = 0
        rb.status = Status.RUNNING


@njit(cache=True)
def advance(robots, noise, npos, traj, pt, st, active):
    """Run every ``active`` robot's primitive until it is DONE or needs the caller.

    ``noise[i, npos[i]:]``: robot ``i``'s unused normals (wheel noise); ``traj[i]`` receives
    the pose after every step when ``traj.shape[1] > 0``; ``pt``, ``st``: ``tuple`` of a
    :class:`Params`, a :class:`Scratch`. A robot left at ``NOISE`` wants its normals
    refilled, one at ``CHECK`` wants to know whether the disc at its pose touches a shape it
    did not touch before the step (the caller sets ``CONTACT`` if so); then call again.
    """
    p, s = Params(*pt), Scratch(*st)
    prof = Profiles(p.turn_caps, p.turn_sums, p.drive_caps, p.drive_sums)
    for i in range(robots.shape[0]):
        if not active[i]:
            continue
        rb = robots[i]
        if rb.status == Status.DONE or rb.status == Status.IDLE:
            continue
        if rb.status == Status.CONTACT:
            _bump(rb, p, s)
            continue
        if rb.status == Status.CHECK:  # no contact began: finish that step (the solve)
            _solve(rb, p)
            rb.sub += 1
        rb.status = Status.RUNNING
        while True:
            if rb.phase == Phase.PLAN:
                if not _plan(rb, p, prof):
                    _done(rb, p, reached=True)
                    break
                rb.phase = Phase.GUARD
            if rb.phase == Phase.GUARD:
                _guard_leg(rb, p, s)
                rb.phase = Phase.DRIVE
            if _drive_leg(rb, noise[i], npos[i:i + 1], traj[i], p, s, prof):
                break  # handed back to the caller
            if _finish_leg(rb, p):
                break


@njit(cache=True)
def _plan(rb, p, prof):
    """Plan a leg from the pose (:func:`plan_leg`); False when there is nothing to do."""
    leg = plan_leg(rb.x, rb.y, rb.th, rb.tx, rb.ty, rb.head, p.tol_m, p.period, prof)
    rb.nturn, rb.tsign, rb.tscale = leg.nturn, leg.tsign, leg.tscale
    rb.ndrive, rb.dscale, rb.ex, rb.ey, rb.dist = (leg.ndrive, leg.dscale, leg.ex, leg.ey,
                                                   leg.dist)
    rb.cmd = rb.sub = 0
    rb.cmd_set = -1
    return leg.nturn > 0 or leg.ndrive > 0


@njit(cache=True)
def _guard_leg(rb, p, s):
    """At ``exact``, a drive leg's guard: how far the disc may go from the leg's start
    (cached per (cell, action) for legs that start on their cell centre). Above ``exact``
    every step has its own (:func:`_step`): the leg has none."""
    rb.limit = math.inf
    if rb.ndrive == 0 or p.wheel_noise > 0.0 or p.carried:
        return
    cx, cy = (rb.cell_x + 0.5) * p.cell_m, (rb.cell_y + 0.5) * p.cell_m
    cell, a = rb.cell_y * p.nx + rb.cell_x, rb.action
    on_centre = abs(rb.x - cx) <= CENTRE_TOL_M and abs(rb.y - cy) <= CENTRE_TOL_M
    if on_centre and not math.isnan(s.guards[cell, a]):
        free = s.guards[cell, a]
    else:  # cast the leg: from the exact centre when on it (then cached)
        x0, y0 = (cx, cy) if on_centre else (rb.x, rb.y)
        alpha = _sweep(p, s, x0, y0, rb.tx, rb.ty)
        free = math.inf if alpha == math.inf else alpha * math.hypot(rb.tx - x0, rb.ty - y0)
        s.counters[1] += 1
        if on_centre:
            s.guards[cell, a] = free
    rb.free = free
    rb.gx, rb.gy = rb.x, rb.y
    rb.limit = math.inf if free == math.inf else free + p.depth_m


@njit(cache=True)
def _drive_leg(rb, noise, npos, traj, p, s, prof):
    """Drive the leg's remaining commands; True when the robot was handed back to the caller
    (``NOISE``, ``CHECK``), False when the leg's commands are all driven."""
    leg = Leg(rb.nturn, rb.tsign, rb.tscale, rb.ndrive, rb.dscale, rb.ex, rb.ey, rb.dist)
    while True:
        k = rb.cmd
        if rb.cmd_set != k:  # a new command: its twist, as the wheels deliver it
            vx, vy, w = leg_command(leg, k, prof)
            if math.isnan(w):
                return False
            if p.wheel_noise > 0.0 or p.carried:
                e_left = e_right = 0.0
                if p.wheel_noise > 0.0:
                    j = npos[0]
                    if j + 2 > noise.shape[0]:
                        rb.status = Status.NOISE
                        return True
                    e_left, e_right = noise[j], noise[j + 1]
                    npos[0] = j + 2
                vx, vy, w = wheel_twist(vx, vy, w, rb.th, e_left, e_right, p.wheel_noise,
                                        p.wheel_base_m)
            rb.cvx, rb.cvy, rb.cw = vx, vy, w
            rb.cmd_set = k
        while rb.sub < p.substeps:
            if _step(rb, traj, p, s):
                rb.status = Status.CHECK
                return True
            _solve(rb, p)
            rb.sub += 1
        rb.cmd = k + 1
        rb.sub = 0


@njit(cache=True)
def _step(rb, traj, p, s):
    """One physics step: guard, integrate, (carried pose) the surface's hold and the bumper;
    True when Chipmunk must say whether a contact began."""
    noisy = p.wheel_noise > 0.0 or p.carried
    held = noisy and rb.resting
    vx, vy = rb.vx, rb.vy
    check = False
    depth0 = 0.0
    if noisy:  # this step's own guard, as PhysicsWorld.before_step
        ln = math.hypot(vx, vy) * p.dt
        if ln > 1e-12:
            alpha = _sweep(p, s, rb.x, rb.y, rb.x + vx * p.dt, rb.y + vy * p.dt)
            if alpha < math.inf and alpha * ln + p.depth_m < ln:
                scale = (alpha * ln + p.depth_m) / ln
                vx, vy = vx * scale, vy * scale
                rb.vx, rb.vy = vx, vy
        if held:
            depth0 = _depth(p, s, rb.x, rb.y)
    elif rb.limit < math.inf:  # the leg's guard
        done = (rb.x - rb.gx) * rb.ex + (rb.y - rb.gy) * rb.ey
        if done + p.dt * (vx * rb.ex + vy * rb.ey) > rb.limit:
            u = max(rb.limit - done, 0.0) / p.dt
            vx, vy = u * rb.ex, u * rb.ey
            rb.vx, rb.vy = vx, vy
    rb.px, rb.py, rb.pth = rb.x, rb.y, rb.th
    rb.x = rb.px + vx * p.dt
    rb.y = rb.py + vy * p.dt
    rb.th = rb.pth + rb.w * p.dt
    rb.steps += 1
    if held:
        depth1 = _depth(p, s, rb.x, rb.y)
        if depth1 > depth0 + DEEPER_M:  # pushes into what it rests on
            into = _held(rb, p, s)
            if not (rb.nturn > 0 and rb.cmd <= rb.nturn):  # a drive presses the bumper
                rb.press += into
                if rb.press >= p.bumper_travel_m:  # a bump; it stays where it was
                    rb.forced = check = True
                    rb.x, rb.y, rb.th = rb.px, rb.py, rb.pth
        elif depth1 <= 0.0:
            rb.resting = False
    if noisy:
        check = check or _new_touch(p, s, rb.px, rb.py, rb.x, rb.y)
    elif rb.limit < math.inf:
        along = (rb.x - rb.gx) * rb.ex + (rb.y - rb.gy) * rb.ey
        check = along > rb.free - CHECK_MARGIN_M
    if rb.ntraj < traj.shape[0]:
        traj[rb.ntraj, 0], traj[rb.ntraj, 1], traj[rb.ntraj, 2] = rb.x, rb.y, rb.th
        rb.ntraj += 1
    return check


@njit(cache=True, inline="always")
def _solve(rb, p):
    """The joints' velocity solve: the robot's twist becomes the control body's, moved by no
    more than the joints' accumulated-impulse clamps allow (pivot: by length; gear)."""
    dvx, dvy, dw = rb.cvx - rb.vx, rb.cvy - rb.vy, rb.cw - rb.w
    if dvx * dvx + dvy * dvy <= p.dv_max * p.dv_max:
        rb.vx, rb.vy = rb.cvx, rb.cvy
    else:
        d = math.hypot(dvx, dvy)
        rb.vx, rb.vy = rb.vx + dvx * (p.dv_max / d), rb.vy + dvy * (p.dv_max / d)
    rb.w = rb.cw if abs(dw) <= p.dw_max else rb.w + math.copysign(p.dw_max, dw)


@njit(cache=True)
def _held(rb, p, s):
    """The surface holds the disc: take away the part of the last step that went into it
    (along the surface normal, from central differences of the overlap depth) and return
    how far that was [m] (the bumper's press). As :meth:`PhysicsWorld.hold`."""
    h = HOLD_STEP_M
    x, y = rb.x, rb.y
    gx = _depth(p, s, x + h, y) - _depth(p, s, x - h, y)  # grows into the surface
    gy = _depth(p, s, x, y + h) - _depth(p, s, x, y - h)
    g = math.hypot(gx, gy)
    if g == 0.0:
        return 0.0
    nx, ny = gx / g, gy / g
    into = (x - rb.px) * nx + (y - rb.py) * ny
    if into <= 0.0:
        return 0.0
    rb.x, rb.y = x - into * nx, y - into * ny
    return into


@njit(cache=True)
def _finish_leg(rb, p):
    """The leg's commands are driven without a contact: done (reached, or out of time), or
    plan the next leg from the pose. True when done."""
    if at_target(rb.x, rb.y, rb.th, rb.tx, rb.ty, rb.head, p.tol_m, p.tol_rad):
        _done(rb, p, reached=True)
        return True
    if rb.steps - rb.steps0 >= p.timeout_steps:
        rb.timeout = True
        _done(rb, p, reached=False)
        return True
    rb.phase = Phase.PLAN
    return False


@njit(cache=True)
def _bump(rb, p, s):
    """A contact began (booked by the caller): the primitive ends with the robot and the
    control body at rest; with carried pose where it is (before the last step when that
    pressed the bumper home), resting; otherwise back on its start cell's centre (above
    ``exact`` resting there if that centre overlaps a shape: noise lets a robot stop within
    tolerance of a centre that is not clear)."""
    rb.vx = rb.vy = rb.w = rb.cvx = rb.cvy = rb.cw = 0.0
    rb.bumped = True
    rb.forced = False
    if p.carried:
        rb.resting = True
    else:
        rb.x = (rb.cell_x + 0.5) * p.cell_m
        rb.y = (rb.cell_y + 0.5) * p.cell_m
        rb.resting = p.wheel_noise > 0.0 and _depth(p, s, rb.x, rb.y) > 0.0
    _done(rb, p, reached=False)


@njit(cache=True)
def _done(rb, p, reached):
    rb.reached = reached
    ix, iy = cell_of(rb.x, rb.y, p.cell_m, p.nx, p.ny)
    rb.state = iy * p.nx + ix
    rb.status = Status.DONE


@njit(cache=True)
def _new_touch(p, s, x0, y0, x1, y1):
    """Whether the disc at (x1, y1) comes within CHECK_MARGIN_M of a shape it did not overlap
    at (x0, y0). A swept guard cannot tell: Munk2D's segment query skips a face the disc moves
    along within 10 um of parallel, and the surface's hold moves the disc off its sweep."""
    r, m = p.radius_m, CHECK_MARGIN_M
    for k in range(p.walls.shape[0]):
        w = p.walls[k]
        if (_segment_distance(x1, y1, w[0], w[1], w[2], w[3]) - w[4] - r < m
                and _segment_distance(x0, y0, w[0], w[1], w[2], w[3]) - w[4] - r > -m):
            return True
    s.counters[0] += 1
    ix0, iy0 = cell_of(x1 - r - m, y1 - r - m, p.cell_m, p.nx, p.ny)
    ix1, iy1 = cell_of(x1 + r + m, y1 + r + m, p.cell_m, p.nx, p.ny)
    for gy in range(iy0, iy1 + 1):
        for gx in range(ix0, ix1 + 1):
            cell = gy * p.nx + gx
            for q in range(p.grid_start[cell], p.grid_start[cell + 1]):
                k = p.grid_items[q]
                if s.seen[k] != s.counters[0]:
                    s.seen[k] = s.counters[0]
                    if _clear(p, k, x1, y1) < m and _clear(p, k, x0, y0) > -m:
                        return True
    return False


@njit(cache=True, inline="always")
def _clear(p, k, x, y):
    """Clearance [m] of the disc at (x, y) from grid item ``k`` (circles, then boxes)."""
    if k < p.circles.shape[0]:
        c = p.circles[k]
        return math.hypot(x - c[0], y - c[1]) - c[2] - p.radius_m
    b = p.boxes[k - p.circles.shape[0]]
    return _box_distance(x, y, b[0], b[1], b[2], b[3]) - p.radius_m


@njit(cache=True, inline="always")
def _sweep(p, s, ax, ay, bx, by):
    s.counters[0] += 1
    return sweep_fraction(p.circles, p.walls, p.boxes, p.cell_m, p.nx, p.ny, p.grid_start,
                          p.grid_items, s.seen, s.counters[0], p.radius_m, ax, ay, bx, by)


@njit(cache=True, inline="always")
def _depth(p, s, x, y):
    s.counters[0] += 1
    return overlap_depth(p.circles, p.walls, p.boxes, p.cell_m, p.nx, p.ny, p.grid_start,
                         p.grid_items, s.seen, s.counters[0], p.radius_m, x, y)

"""Motion primitives for many robots at once, in compiled code: Chipmunk's own integration
where nothing can touch, Chipmunk itself (through :mod:`sim.physics.batch`) where something might.

Why this is the same physics as :class:`sim.physics.world.PhysicsWorld`. The robot is
pulled by a kinematic control body through a pivot and a gear joint with ``max_bias = 0``
whose force limits exceed what the wheel limits ask for (see :mod:`sim.physics.world`).
Away from contacts Chipmunk's step therefore does, per robot:

1. ``p += v * dt``, ``theta += omega * dt`` (position integrates first, with the velocity
   the last solve left; ``v_bias = 0`` because ``collision_bias = 1``);
2. collision detection (nothing overlaps: no arbiter);
3. velocity solve: the joints drive ``(v, omega)`` to the control body's twist exactly
   (to rounding: the joint's effective mass is the robot's own, its impulse clamp is
   never reached).

:func:`advance` performs 1 and 3 in float64 in the same order. Step 2 can only matter on
a drive leg whose swept disc meets a surface (the leg's guard, cast once with Chipmunk):
every step that ends within :data:`CHECK_MARGIN_M` of that surface, or past it, is handed
back with status ``CHECK`` and the caller asks Chipmunk's collision detection
(``cpSpaceShapeQuery``, the narrow phase ``cpSpaceStep`` runs) whether a contact began.
A disc turning about its centre sweeps nothing, so a turn in place begins no contact;
with carried pose a robot resting against a surface is held by it (see :func:`advance`).
The guard itself is cast in compiled code with Chipmunk's own segment-query formulas
(:mod:`sim.physics.sweep`), once per (cell, action) for legs that start on their cell
centre and once per leg otherwise. The controller (turn in place, stop, drive,
stop; minimal-time discrete profiles; tolerances; timeout) is
:class:`sim.physics.controller.PrimitiveController`'s, written over arrays.

Agreement with the reference world (every step through ``cpSpaceStep``) is tested over
thousands of random primitives on two maps, bumps included: same cells, rewards,
contacts and step counts, poses within 1e-9 m.

State is a float64 array ``fs[N, NF]`` and an int64 array ``ist[N, NI]`` whose columns are
named below (``X``, ``Y``, ... and ``STATUS``, ``STEPS``, ...).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sim.physics.sweep import overlap_depth, sweep_fraction

# float columns of fs
X, Y, TH = 0, 1, 2  # pose [m, m, rad] (heading not wrapped)
VX, VY, W = 3, 4, 5  # robot velocity after the last solve [m/s, m/s, rad/s]
CVX, CVY, CW = 6, 7, 8  # control body twist held now
TX, TY, HEAD = 9, 10, 11  # primitive target centre [m] and cardinal heading [rad]
SX, SY = 12, 13  # start cell centre [m] (where a bump places the robot back)
EX, EY, DIST = 14, 15, 16  # drive direction (unit) and length of the current leg [m]
GX, GY, LIMIT = 17, 18, 19  # guard: leg start and allowed advance (inf: nothing in the way)
TSCALE, DSCALE, TSIGN = 20, 21, 22  # scale of the turn / drive profiles, turn direction
FREE = 23  # free distance of the leg from its start [m] (inf: none); also the cast answer
PX, PY, PTH = 24, 25, 26  # pose before the step being checked
PRESS = 27  # carried pose: how far the drive has pressed the bumper this primitive [m]
NF = 28

# int columns of ist
STATUS, STEPS, STEPS0 = 0, 1, 2
CELLX, CELLY, ACTION = 3, 4, 5
NTURN, NDRIVE, CMD, SUB = 6, 7, 8, 9  # leg: periods of turn / drive; command, substep now
BUMPED, REACHED, TIMEOUT = 10, 11, 12
LEG = 13  # 0 = plan a new leg; 1 = leg planned, guard pending; 2 = driving
CLAMPED = 14  # the step being checked had its velocity shortened by the guard
NCONTACT = 15  # contacts that began during the primitive
CMDSET = 16  # index of the command whose (possibly perturbed) twist is in CVX..CW; -1: none
INCONTACT = 17  # carried pose: the robot rests against something (it may slide, not push)
FORCED = 18  # the step being checked pushed deeper into what the robot rests against
NI = 19

# STATUS codes
IDLE, RUNNING, NOISE, CHECK, DONE = 0, 1, 2, 3, 4  # NOISE: refill the robot's normals

CHECK_MARGIN_M = 1e-6  # steps ending this close to the guard's surface ask Chipmunk [m]
CENTRE_TOL_M = 1e-9  # a leg starting this close to its cell centre uses the cached guard [m]
MIN_TURN_RAD = 1e-9  # as sim.physics.controller.MIN_TURN_RAD


def profile_arrays(table, largest_total: float) -> tuple[np.ndarray, np.ndarray]:
    """``(caps[n, n], sums[n])`` of a :class:`ProfileTable`, grown past ``largest_total``."""
    table.profile(largest_total)
    n = len(table.caps)
    caps = np.zeros((n, n))
    for i, row in enumerate(table.caps):
        caps[i, : len(row)] = row
    return caps, np.asarray(table.sums, dtype=np.float64)


@njit(cache=True, inline="always")
def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True, inline="always")
def _periods(sums, total):
    """bisect_left(sums, total), -1 when the table is too short."""
    lo, hi = 0, sums.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if sums[mid] < total:
            lo = mid + 1
        else:
            hi = mid
    return lo if lo < sums.shape[0] else -1


@njit(cache=True)
def begin(fs, ist, i, action, cell_m, nx, ny, deltas, headings):
    """Start grid ``action`` for robot ``i`` from its current pose (its cell as the
    discretiser says, clamped into the grid)."""
    cell_x = min(max(int(math.floor(fs[i, X] / cell_m)), 0), nx - 1)  # noqa: RUF046 (numba)
    cell_y = min(max(int(math.floor(fs[i, Y] / cell_m)), 0), ny - 1)  # noqa: RUF046 (numba)
    ist[i, CELLX], ist[i, CELLY], ist[i, ACTION] = cell_x, cell_y, action
    fs[i, TX] = (cell_x + deltas[action, 0] + 0.5) * cell_m
    fs[i, TY] = (cell_y + deltas[action, 1] + 0.5) * cell_m
    fs[i, HEAD] = headings[action]
    fs[i, SX] = (cell_x + 0.5) * cell_m
    fs[i, SY] = (cell_y + 0.5) * cell_m
    ist[i, STEPS0] = ist[i, STEPS]
    ist[i, BUMPED] = 0
    ist[i, REACHED] = 0
    ist[i, TIMEOUT] = 0
    ist[i, NCONTACT] = 0
    ist[i, LEG] = 0
    ist[i, CMDSET] = -1
    ist[i, FORCED] = 0
    fs[i, PRESS] = 0.0
    ist[i, STATUS] = RUNNING


@njit(cache=True)
def _plan(fs, ist, i, period, tol_m, turn_caps, turn_sums, drive_caps, drive_sums):
    """Plan a leg from the pose (turn to face the target, drive); False when nothing to do."""
    dx = fs[i, TX] - fs[i, X]
    dy = fs[i, TY] - fs[i, Y]
    dist = math.hypot(dx, dy)
    drive = dist > tol_m
    turn = _wrap((math.atan2(dy, dx) if drive else fs[i, HEAD]) - fs[i, TH])
    nturn = 0
    if abs(turn) > MIN_TURN_RAD:
        total = abs(turn) / period
        n = _periods(turn_sums, total)
        if n < 0:
            raise ValueError("turn longer than the profile table")
        nturn = n + 1
        fs[i, TSCALE] = total / turn_sums[n]
        fs[i, TSIGN] = -1.0 if turn < 0.0 else 1.0
    ndrive = 0
    if drive:
        total = dist / period
        n = _periods(drive_sums, total)
        if n < 0:
            raise ValueError("drive longer than the profile table")
        ndrive = n + 1
        fs[i, DSCALE] = total / drive_sums[n]
        fs[i, EX] = dx / dist
        fs[i, EY] = dy / dist
        fs[i, DIST] = dist
    else:
        fs[i, DIST] = 0.0
    ist[i, NTURN] = nturn
    ist[i, NDRIVE] = ndrive
    ist[i, CMD] = 0
    ist[i, SUB] = 0
    ist[i, CMDSET] = -1
    return nturn > 0 or ndrive > 0


@njit(cache=True, inline="always")
def _command(fs, ist, i, k, turn_caps, drive_caps):
    """Twist (vx, vy, omega) of command ``k`` of the leg; -1 omega marker past the end."""
    nturn, ndrive = ist[i, NTURN], ist[i, NDRIVE]
    if nturn > 0:
        if k < nturn:
            return 0.0, 0.0, fs[i, TSIGN] * (turn_caps[nturn - 1, k] * fs[i, TSCALE])
        if k == nturn:
            return 0.0, 0.0, 0.0
        k -= nturn + 1
    if ndrive > 0:
        if k < ndrive:
            u = drive_caps[ndrive - 1, k] * fs[i, DSCALE]
            return u * fs[i, EX], u * fs[i, EY], 0.0
        if k == ndrive:
            return 0.0, 0.0, 0.0
    return math.nan, math.nan, math.nan


@njit(cache=True)
def advance(fs, ist, active, dt, substeps, period, tol_m, tol_rad, timeout_steps, depth_m,
            cell_m, nx, ny, guards, turn_caps, turn_sums, drive_caps, drive_sums, traj, ntraj,
            radius_m, circles, walls, boxes, grid_start, grid_items, seen, stamp, casts,
            wheel_noise, carried, half_base_m, noise, npos, bumper_travel_m):
    """Run every ``active`` robot's primitive until it is DONE or needs Chipmunk.

    ``guards[cell, action]``: free distance of the drive leg from that cell's centre to
    the neighbour's centre (inf: nothing in the way; nan: not cast yet), filled here by
    :func:`sim.physics.sweep.sweep_fraction` over the static geometry (``circles`` ...
    ``grid_items``; ``seen``/``stamp`` dedupe candidates; ``casts[0]`` counts). ``traj[i]``
    receives the pose after every step when ``traj.shape[1] > 0`` (``ntraj[i]`` counts).
    Robots left with status CHECK want to know whether the disc at (X, Y) touches
    anything; resume by calling again with the answer applied (see :mod:`sim.physics.batch`).

    A robot resting against a surface (carried pose, ``INCONTACT``) is held by it: a step
    that would carry it deeper keeps only its motion along the surface (and its turn). On
    a drive leg the motion taken away presses the bumper (``PRESS``); at
    ``bumper_travel_m`` the bumper reports a bump. On a turn leg nothing presses: a turn
    in place against a surface turns.
    """
    record = traj.shape[1] > 0
    noisy = wheel_noise > 0.0 or carried  # per-step guards; twists follow the heading
    for i in range(fs.shape[0]):
        if not active[i]:
            continue
        st = ist[i, STATUS]
        if st == DONE or st == IDLE:
            continue
        if st == CHECK:  # Chipmunk said: no contact began; finish that step (the solve)
            cvx, cvy, cw, = fs[i, CVX], fs[i, CVY], fs[i, CW]
            fs[i, VX], fs[i, VY], fs[i, W] = cvx, cvy, cw
            ist[i, STATUS] = RUNNING
            ist[i, SUB] += 1
        elif st == NOISE:  # the caller refilled this robot's normals
            ist[i, STATUS] = RUNNING
        while True:
            if ist[i, LEG] == 0:
                if not _plan(fs, ist, i, period, tol_m, turn_caps, turn_sums, drive_caps,
                             drive_sums):
                    ist[i, REACHED] = 1
                    ist[i, STATUS] = DONE
                    break
                ist[i, LEG] = 1
            if ist[i, LEG] == 1:
                fs[i, LIMIT] = math.inf
                if ist[i, NDRIVE] > 0 and not noisy:
                    cx = (ist[i, CELLX] + 0.5) * cell_m
                    cy = (ist[i, CELLY] + 0.5) * cell_m
                    s = ist[i, CELLY] * nx + ist[i, CELLX]
                    a = ist[i, ACTION]
                    on_centre = (abs(fs[i, X] - cx) <= CENTRE_TOL_M
                                 and abs(fs[i, Y] - cy) <= CENTRE_TOL_M)
                    if on_centre and not math.isnan(guards[s, a]):
                        fs[i, FREE] = guards[s, a]
                    else:  # cast the leg: from the exact centre when on it (cached)
                        x0 = cx if on_centre else fs[i, X]
                        y0 = cy if on_centre else fs[i, Y]
                        tx, ty = fs[i, TX], fs[i, TY]
                        stamp[0] += 1
                        alpha = sweep_fraction(circles, walls, boxes, cell_m, nx, ny,
                                               grid_start, grid_items, seen, stamp[0],
                                               radius_m, x0, y0, tx, ty)
                        free = (math.inf if alpha == math.inf
                                else alpha * math.hypot(tx - x0, ty - y0))
                        casts[0] += 1
                        if on_centre:
                            guards[s, a] = free
                        fs[i, FREE] = free
                    _set_guard(fs, i, depth_m)
                ist[i, LEG] = 2
            # drive the leg's commands
            stop = False
            while True:
                k = ist[i, CMD]
                if ist[i, CMDSET] == k:  # resumed inside this command: keep its twist
                    cvx, cvy, cw = fs[i, CVX], fs[i, CVY], fs[i, CW]
                else:
                    cvx, cvy, cw = _command(fs, ist, i, k, turn_caps, drive_caps)
                    if math.isnan(cw):
                        break
                    if noisy:
                        if wheel_noise > 0.0 and npos[i] + 2 > noise.shape[1]:
                            ist[i, STATUS] = NOISE
                            stop = True
                            break
                        cvx, cvy, cw = _perturbed(fs, i, cvx, cvy, cw, wheel_noise,
                                                  half_base_m, noise, npos)
                    fs[i, CVX], fs[i, CVY], fs[i, CW] = cvx, cvy, cw
                    ist[i, CMDSET] = k
                while ist[i, SUB] < substeps:
                    vx, vy = fs[i, VX], fs[i, VY]
                    clamped = 0
                    candidate = False
                    depth0 = 0.0
                    if noisy:  # guard this step: its own sweep, as DiffDrive's advance does
                        ln = math.hypot(vx, vy) * dt
                        if ln > 1e-12:
                            stamp[0] += 1
                            alpha = sweep_fraction(circles, walls, boxes, cell_m, nx, ny,
                                                   grid_start, grid_items, seen, stamp[0],
                                                   radius_m, fs[i, X], fs[i, Y],
                                                   fs[i, X] + vx * dt, fs[i, Y] + vy * dt)
                            if alpha < math.inf:
                                free = alpha * ln
                                if free + depth_m < ln:
                                    scale = (free + depth_m) / ln
                                    vx, vy = vx * scale, vy * scale
                                    fs[i, VX], fs[i, VY] = vx, vy
                                    clamped = 1
                                candidate = math.hypot(vx, vy) * dt > free - CHECK_MARGIN_M
                        if ist[i, INCONTACT] == 1:
                            stamp[0] += 1
                            depth0 = overlap_depth(circles, walls, boxes, cell_m, nx, ny,
                                                   grid_start, grid_items, seen, stamp[0],
                                                   radius_m, fs[i, X], fs[i, Y])
                    elif fs[i, LIMIT] < math.inf:
                        ex, ey = fs[i, EX], fs[i, EY]
                        done = (fs[i, X] - fs[i, GX]) * ex + (fs[i, Y] - fs[i, GY]) * ey
                        if done + dt * (vx * ex + vy * ey) > fs[i, LIMIT]:
                            u = max(fs[i, LIMIT] - done, 0.0) / dt
                            vx, vy = u * ex, u * ey
                            fs[i, VX], fs[i, VY] = vx, vy
                            clamped = 1
                    px, py, pth = fs[i, X], fs[i, Y], fs[i, TH]
                    fs[i, X] = px + vx * dt
                    fs[i, Y] = py + vy * dt
                    fs[i, TH] = pth + fs[i, W] * dt
                    ist[i, STEPS] += 1
                    if record:
                        n = ntraj[i]
                        if n < traj.shape[1]:
                            traj[i, n, 0] = fs[i, X]
                            traj[i, n, 1] = fs[i, Y]
                            traj[i, n, 2] = fs[i, TH]
                            ntraj[i] = n + 1
                    if noisy:
                        if ist[i, INCONTACT] == 1:
                            stamp[0] += 1
                            depth1 = overlap_depth(circles, walls, boxes, cell_m, nx, ny,
                                                   grid_start, grid_items, seen, stamp[0],
                                                   radius_m, fs[i, X], fs[i, Y])
                            if depth1 > depth0 + 1e-12:  # pushes into what it rests on
                                into = _held(fs, i, circles, walls, boxes, cell_m, nx, ny,
                                             grid_start, grid_items, seen, stamp, radius_m,
                                             depth0)
                                k_now = ist[i, CMD]
                                turning = ist[i, NTURN] > 0 and k_now <= ist[i, NTURN]
                                if not turning:
                                    fs[i, PRESS] += into
                                    if fs[i, PRESS] >= bumper_travel_m:
                                        ist[i, FORCED] = 1
                                        candidate = True
                            elif depth1 <= 0.0:
                                ist[i, INCONTACT] = 0
                        if candidate:
                            fs[i, PX], fs[i, PY], fs[i, PTH] = px, py, pth
                            ist[i, CLAMPED] = clamped
                            ist[i, STATUS] = CHECK
                            stop = True
                            break
                    elif fs[i, LIMIT] < math.inf:
                        along = ((fs[i, X] - fs[i, GX]) * fs[i, EX]
                                 + (fs[i, Y] - fs[i, GY]) * fs[i, EY])
                        if along > fs[i, FREE] - CHECK_MARGIN_M:
                            fs[i, PX], fs[i, PY], fs[i, PTH] = px, py, pth
                            ist[i, CLAMPED] = clamped
                            ist[i, STATUS] = CHECK
                            stop = True
                            break
                    fs[i, VX], fs[i, VY], fs[i, W] = cvx, cvy, cw  # the joints' solve
                    ist[i, SUB] += 1
                if stop:
                    break
                ist[i, CMD] = k + 1
                ist[i, SUB] = 0
            if stop:
                break
            # leg finished without contact
            dxe = fs[i, TX] - fs[i, X]
            dye = fs[i, TY] - fs[i, Y]
            if (math.hypot(dxe, dye) <= tol_m
                    and abs(_wrap(fs[i, TH] - fs[i, HEAD])) <= tol_rad):
                ist[i, REACHED] = 1
                ist[i, STATUS] = DONE
                break
            if ist[i, STEPS] - ist[i, STEPS0] >= timeout_steps:
                ist[i, TIMEOUT] = 1
                ist[i, STATUS] = DONE
                break
            ist[i, LEG] = 0


@njit(cache=True)
def _held(fs, i, circles, walls, boxes, cell_m, nx, ny, grid_start, grid_items, seen, stamp,
          radius_m, depth0):
    """The surface holds the disc: take away the part of the last step that went into it
    (along the surface normal, from central differences of the overlap depth) and return
    how far that was [m] (the bumper's press). If the disc would still end deeper than
    ``depth0`` (a corner, where the deepest surface changes within the step), the step's
    translation is taken away whole: a resting robot never sinks into what holds it."""
    h = 1e-5
    x, y = fs[i, X], fs[i, Y]
    d0 = d1 = d2 = d3 = 0.0
    for j in range(4):
        qx = x + (h if j == 0 else -h if j == 1 else 0.0)
        qy = y + (h if j == 2 else -h if j == 3 else 0.0)
        stamp[0] += 1
        d = overlap_depth(circles, walls, boxes, cell_m, nx, ny, grid_start, grid_items,
                          seen, stamp[0], radius_m, qx, qy)
        if j == 0:
            d0 = d
        elif j == 1:
            d1 = d
        elif j == 2:
            d2 = d
        else:
            d3 = d
    gx, gy = d0 - d1, d2 - d3  # grows into the surface
    g = math.hypot(gx, gy)
    into = 0.0
    if g > 0.0:
        ux, uy = gx / g, gy / g
        into = (x - fs[i, PX]) * ux + (y - fs[i, PY]) * uy
        if into > 0.0:
            fs[i, X] = x - into * ux
            fs[i, Y] = y - into * uy
        else:
            into = 0.0
    stamp[0] += 1
    after = overlap_depth(circles, walls, boxes, cell_m, nx, ny, grid_start, grid_items,
                          seen, stamp[0], radius_m, fs[i, X], fs[i, Y])
    if after > depth0 + 1e-12:  # still deeper: hold the disc where it was
        into = max(into, math.hypot(x - fs[i, PX], y - fs[i, PY]))
        fs[i, X], fs[i, Y] = fs[i, PX], fs[i, PY]
    return into


@njit(cache=True, inline="always")
def _perturbed(fs, i, cvx, cvy, cw, wheel_noise, half_base_m, noise, npos):
    """The command as the wheels deliver it: each wheel's speed times (1 + sigma * e), e from
    the robot's normals; the twist then moves along the robot's heading (a diff drive)."""
    v = math.hypot(cvx, cvy)
    vl, vr = v - cw * half_base_m, v + cw * half_base_m
    if wheel_noise > 0.0:
        k = npos[i]
        vl *= 1.0 + wheel_noise * noise[i, k]
        vr *= 1.0 + wheel_noise * noise[i, k + 1]
        npos[i] = k + 2
    v2 = 0.5 * (vl + vr)
    w2 = (vr - vl) / (2.0 * half_base_m)
    th = fs[i, TH]
    return v2 * math.cos(th), v2 * math.sin(th), w2


@njit(cache=True, inline="always")
def _set_guard(fs, i, depth_m):
    fs[i, GX] = fs[i, X]
    fs[i, GY] = fs[i, Y]
    free = fs[i, FREE]
    fs[i, LIMIT] = math.inf if free == math.inf else free + depth_m


@njit(cache=True)
def begin_all(fs, ist, actions, active, cell_m, nx, ny, deltas, headings):
    """:func:`begin` for every active robot."""
    for i in range(fs.shape[0]):
        if active[i]:
            begin(fs, ist, i, actions[i], cell_m, nx, ny, deltas, headings)


@njit(cache=True, inline="always")
def _at_rest(fs, ist, i):
    """The primitive ended in a bump: robot and control body at rest."""
    for k in (VX, VY, W, CVX, CVY, CW):
        fs[i, k] = 0.0
    ist[i, BUMPED] = 1
    ist[i, STATUS] = DONE


@njit(cache=True)
def bump_back(fs, ist, i):
    """A contact began: the primitive ends; the robot is placed at rest on its start centre."""
    fs[i, X] = fs[i, SX]
    fs[i, Y] = fs[i, SY]
    _at_rest(fs, ist, i)


@njit(cache=True)
def bump_stay(fs, ist, i, revert):
    """A contact began with carried pose: the robot stops where it is (or, when the step
    pushed into what it rested on, where it was before that step), at rest."""
    if revert:
        fs[i, X], fs[i, Y], fs[i, TH] = fs[i, PX], fs[i, PY], fs[i, PTH]
    _at_rest(fs, ist, i)
    ist[i, INCONTACT] = 1
    ist[i, FORCED] = 0


@njit(cache=True)
def states_of(fs, cell_m, nx, ny, out):
    """Discretiser.state_of for every robot (clamped into the grid)."""
    for i in range(fs.shape[0]):
        cx = int(math.floor(fs[i, X] / cell_m))  # noqa: RUF046 (numba)
        cy = int(math.floor(fs[i, Y] / cell_m))  # noqa: RUF046 (numba)
        cx = min(max(cx, 0), nx - 1)
        cy = min(max(cy, 0), ny - 1)
        out[i] = cy * nx + cx
    return out

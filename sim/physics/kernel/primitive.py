"""Motion primitives for many robots at once, in compiled code: Chipmunk's own integration
where nothing can touch, Chipmunk's collision formulas where something might.

Why this is the physics of the reference world (:class:`sim.physics.reference.world.PhysicsWorld`
driven by :class:`sim.physics.reference.controller.PrimitiveController`). The robot is pulled by a
kinematic control body through a pivot and a gear joint with ``max_bias = 0`` (see
:mod:`sim.physics.reference.world`). Away from contacts Chipmunk's step does, per robot:

1. ``p += v * dt``, ``theta += omega * dt`` (position integrates first, with the velocity
   the last solve left; ``v_bias = 0`` because ``collision_bias = 1``);
2. collision detection (nothing overlaps: no arbiter);
3. velocity solve: the joints drive ``(v, omega)`` to the control body's twist exactly (to
   rounding: the joint's effective mass is the robot's own), or by their impulse limit
   (``max_force * dt``, the wheels' traction) when noise or a guard-shortened step asks
   for more.

:func:`advance` performs 1 and 3 in float64 in the same order. Step 2 matters only where
the disc may touch something: at ``exact`` where the leg's swept-disc guard (cast with
Chipmunk's segment-query formulas, :mod:`sim.physics.kernel.sweep`; cached per (cell, action) for
legs from a cell centre) says the step ends at its surface; above ``exact`` where the step's
own sweep meets a surface or, where a sweep can be blind (a step along a box face within
10 um of parallel, a hold), the disc ends within 1 um of a shape it did not overlap before.
Such a step asks Chipmunk's narrow phase (``cpSpaceShapeQuery``'s collision formulas,
compiled: :mod:`sim.physics.kernel.narrow_phase`) whether a contact began; where that cannot be
sure of Chipmunk's answer the step is handed back (``CHECK``) and the caller asks Chipmunk.
The controller is the controller module's compiled functions
(:func:`sim.physics.reference.controller.plan_leg`, ``leg_command``, ``wheel_twist``, ``at_target``,
``cell_of``), the geometry's answers
:mod:`sim.physics.kernel.queries`; the fidelity knobs follow the reference's
rules (:meth:`PrimitiveController.run`), tested field by field at ``exact``, wheel noise
only and ``noisy``.

State by name (:mod:`sim.physics.kernel.state`): each robot is a record of ``ROBOT``
(``rb = robots[i]`` in compiled code, a reference: ``rb.x``), a batch's constants one
``Params``, its tables ``Profiles`` and ``Geometry``, its caches ``Scratch``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS
from sim.physics.drive_profiles import Profiles
from sim.physics.kernel.exact import cast_guard, guard_leg, integrate, step_exact
from sim.physics.kernel.narrow_phase import contacts_began
from sim.physics.kernel.queries import (
    depth_at,
    in_clear_region,
    new_clear_region,
    new_touch,
    odometry,
    sweep_step,
    within,
)
from sim.physics.kernel.state import BORROWS, Geometry, Params, Phase, Scratch, Status
from sim.physics.kernel.wheels import deliver
from sim.physics.motion import (
    SETTLE_M_S,
    Leg,
    arc_of_chord,
    at_target,
    cell_of,
    leg_command,
    plan_leg,
    wheel_twist,
)
from sim.physics.static import DEEPER_M, HOLD_STEP_M

_DELTAS = np.array(ACTION_DELTAS, dtype=np.int64)
_HEADINGS = np.array(ACTION_HEADINGS, dtype=np.float64)


@njit(cache=True)
def begin_all(robots, actions, active, cell_m, nx, ny, localised):
    """Start grid ``actions[i]`` for every ``active`` robot from its pose (its cell as the
    discretiser says, clamped into the grid; with ``localised`` the pose it believes)."""
    for i in range(robots.shape[0]):
        if active[i]:
            begin_one(robots[i], actions[i], cell_m, nx, ny, localised)


@njit(cache=True, inline="always")
def begin_one(rb, a, cell_m, nx, ny, localised):
    """Start grid action ``a`` for one robot from its pose (:func:`begin_all`'s body)."""
    if localised:
        rb.cell_x, rb.cell_y = cell_of(rb.bx, rb.by, cell_m, nx, ny)
    else:
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
    rb.fresh = True


@njit(cache=True)
def advance(robots, noise, npos, nend, traj, contacts, booked, pt, prof_t, geo_t, st,
            active):
    """Run every ``active`` robot's primitive until it is DONE or needs the caller.

    ``noise[i, npos[i]:nend[i]]``: robot ``i``'s unused normals (wheel noise, odometry, fixes);
    ``traj[i]`` receives
    the pose after every step when ``traj.shape[1] > 0``; ``pt``, ``prof_t``, ``geo_t``,
    ``st``: ``tuple`` of a :class:`Params`, :class:`Profiles`, :class:`Geometry`,
    :class:`Scratch`. Where a step may have begun a contact, Chipmunk's narrow phase in
    compiled code (:func:`sim.physics.kernel.narrow_phase.contacts_began`) decides: the contacts
    it finds go to ``contacts[i]`` (``booked[i]`` of them, for the caller to book) and the
    primitive ends in a bump. A robot left at ``NOISE`` wants its normals refilled, one at
    ``CHECK`` a check the compiled phase leaves to Chipmunk (a box within rounding of
    touching): whether the disc at its pose touches a shape it did not touch before the
    step (the caller sets ``CONTACT`` if so); then call again. Returns how many active robots
    wait for the caller (0: every primitive is DONE). Per leg: :func:`_plan`, the guard
    (:mod:`sim.physics.kernel.exact`), its commands (each a control period of physics steps:
    ``step_exact`` at exact; above it the step's own sweep, ``integrate``, :func:`_rest`
    and, where a sweep can be blind, :func:`new_touch`; then :func:`_solve`),
    :func:`_finish_leg`.

    Where a step's sweep can be blind: the hold moved the disc off it; a step shorter than
    10 um loses precision; Munk2D skips a box face (all are axis-aligned) that the disc moves
    along within 10 um of parallel.
    """
    p, prof, g, s = Params(*pt), Profiles(*prof_t), Geometry(*geo_t), Scratch(*st)
    for i in range(robots.shape[0]):
        if active[i]:
            advance_one(i, robots, noise, npos, nend, traj, contacts, booked, p, prof, g, s)
    waiting = 0  # active robots that need the caller (NOISE, CHECK)
    for i in range(robots.shape[0]):
        if active[i] and robots[i].status != Status.DONE:
            waiting += 1
    return waiting


@njit(**BORROWS)
def advance_one(i, robots, noise, npos, nend, traj, contacts, booked, p, prof, g, s):
    """Robot ``i``'s primitive until it is DONE or needs the caller: :func:`advance`'s body
    for one robot, the tuples as named ones (the fused training step calls it per robot)."""
    noisy = (p.wheel_noise > 0.0 or p.carried_pose or p.biased or p.open_loop or p.localisation
             or p.latency or p.slips)
    fixes = p.localisation and p.fix_every > 0
    normals = ((2 if p.wheel_noise > 0.0 else 0) + (3 if p.localisation else 0)  # per command
               + (2 if p.slips else 0))
    rb = robots[i]
    if rb.status == Status.DONE or rb.status == Status.IDLE:
        return
    if rb.status == Status.CONTACT:
        _bump(rb, p, g, s)
        return
    if rb.status == Status.CHECK:  # no contact began: finish that step (the solve)
        _solve(rb, p)
        rb.sub += 1
    rb.status = Status.RUNNING
    while rb.status == Status.RUNNING:
        if rb.fresh:  # the primitive's first call: the fix's normals, when one is due
            if fixes and rb.nfix + 1 >= p.fix_every:
                j = npos[i]
                if j + 3 > nend[i]:
                    rb.status = Status.NOISE
                    break
                rb.f1, rb.f2, rb.f3 = noise[i, j], noise[i, j + 1], noise[i, j + 2]
                npos[i] = j + 3
            rb.fresh = False
        if rb.phase == Phase.PLAN:
            if not _plan(rb, p, prof.turn_sums, prof.drive_sums):
                _done(rb, p, reached=True)
                break
            rb.phase = Phase.GUARD
        if rb.phase == Phase.GUARD:
            rb.limit = math.inf
            if rb.ndrive > 0 and not noisy and not guard_leg(rb, p, s.guards):
                cast_guard(rb, p, g, s)
            rb.phase = Phase.DRIVE
        leg = Leg(rb.nturn, rb.tsign, rb.tscale, rb.ndrive, rb.dscale, rb.ex, rb.ey,
                  rb.dist)
        while rb.status == Status.RUNNING:  # the leg's commands, one per control period
            k = rb.cmd
            if rb.cmd_set != k:  # a new command: its twist, as the wheels deliver it
                vx, vy, w = leg_command(leg, k, prof.turn_caps, prof.drive_caps)
                if math.isnan(w):  # all driven; with latency a stop until settled
                    if not p.latency:
                        break
                    if rb.nleg < 0:
                        rb.nleg = k
                    if (k - rb.nleg >= p.delay
                            and max(abs(rb.wl), abs(rb.wr)) <= SETTLE_M_S):
                        break
                    vx = vy = w = 0.0
                if noisy:
                    e_left = e_right = z_left = z_right = 0.0
                    if normals:
                        j = npos[i]
                        if j + normals > nend[i]:
                            rb.status = Status.NOISE
                            break
                        if p.wheel_noise > 0.0:
                            e_left, e_right = noise[i, j], noise[i, j + 1]
                            j += 2
                        if p.localisation:  # this period's odometry noise
                            rb.o1, rb.o2, rb.o3 = noise[i, j], noise[i, j + 1], noise[i, j + 2]
                            j += 3
                        if p.slips:  # this period's slip draws, one per wheel
                            z_left, z_right = noise[i, j], noise[i, j + 1]
                            j += 2
                        npos[i] = j
                    if p.latency or p.slips:
                        vx, vy, w = deliver(rb, p, vx, vy, w, e_left, e_right, z_left,
                                            z_right)
                    else:
                        vx, vy, w = wheel_twist(vx, vy, w, rb.th, rb.w, p.dt, p.period,
                                                e_left, e_right, p.wheel_noise,
                                                p.wheel_base_m, rb.gain_l, rb.gain_r,
                                                rb.base_k)
                rb.cvx, rb.cvy, rb.cw = vx, vy, w
                rb.cmd_set = k
            while rb.sub < p.substeps:
                if noisy:  # one step above exact, in line (as a call: 15 % slower)
                    held = rb.resting
                    vx, vy = rb.vx, rb.vy
                    ln = 0.0  # the step's length [m], where a sweep or check needs it
                    hit = False
                    clear = False  # the step stays in the robot's clear ball or box
                    if not held:
                        x1, y1 = rb.x + vx * p.dt, rb.y + vy * p.dt
                        clear = in_clear_region(rb, x1, y1)
                        if not clear:
                            new_clear_region(rb, p, g, s)
                            clear = in_clear_region(rb, x1, y1)
                    if not clear:  # (in the ball nothing is within CLEAR_MARGIN_M of the
                        ln = math.hypot(vx, vy) * p.dt  # step: no sweep can hit, no check
                        if ln > 1e-12:  # can find a touch: see new_clear_region)
                            # its own guard, as PhysicsWorld.before_step
                            alpha = sweep_step(p, g, s, rb.x, rb.y, rb.x + vx * p.dt,
                                               rb.y + vy * p.dt)
                            hit = alpha < math.inf
                            if hit and alpha * ln + p.depth_m < ln:
                                scale = (alpha * ln + p.depth_m) / ln
                                vx, vy = vx * scale, vy * scale
                                rb.vx, rb.vy = vx, vy
                    depth0 = depth_at(p, g, s, rb.x, rb.y) if held else 0.0
                    integrate(rb, vx, vy, p)
                    check = hit  # the sweep met a surface: ask Chipmunk
                    if p.localisation:  # the wheels turned (a hold slides them; below)
                        yaw = rb.th - rb.pth  # the wheels turned the arc, not the chord
                        moved = arc_of_chord(math.hypot(vx, vy) * p.dt, yaw)
                        rb.odo_d += moved
                        rb.odo_th += yaw
                    if held and _rest(rb, p, g, s, depth0):
                        check = True  # the bumper pressed home
                        if p.localisation:  # ... before this step's motion: none of it
                            rb.odo_d -= moved
                            rb.odo_th -= yaw
                    elif clear:
                        pass
                    elif not hit and (held or 1e-12 < ln < 1e-5):  # where a sweep is
                        check = new_touch(p, g, s, rb.px, rb.py, rb.x, rb.y, False)
                    elif not hit and ln > 1e-12 and g.boxes.shape[0] and (  # blind
                            abs(rb.x - rb.px) < 1e-5 or abs(rb.y - rb.py) < 1e-5):
                        check = new_touch(p, g, s, rb.px, rb.py, rb.x, rb.y, True)
                else:
                    check = step_exact(rb, p)
                if rb.ntraj < traj.shape[1]:
                    traj[i, rb.ntraj, 0], traj[i, rb.ntraj, 1] = rb.x, rb.y
                    traj[i, rb.ntraj, 2] = rb.th
                    rb.ntraj += 1
                if check:
                    found = contacts_began(rb, p, g, s, contacts[i])
                    if found < 0:  # Chipmunk decides (the caller's check)
                        rb.status = Status.CHECK
                        break
                    if found > 0 or rb.forced:
                        rb.ncontact += found
                        booked[i] = found
                        _bump(rb, p, g, s)
                        break
                _solve(rb, p)
                rb.sub += 1
            if rb.status == Status.RUNNING:
                rb.cmd = k + 1
                rb.sub = 0
                if p.localisation:
                    odometry(rb, p)
        if rb.status == Status.RUNNING:
            _finish_leg(rb, p)


@njit(**BORROWS)
def _plan(rb, p, turn_sums, drive_sums):
    """Plan a leg from the pose (:func:`plan_leg`); False when there is nothing to do. The
    pose is the one the controller knows: the estimate with localisation; in open loop
    without it the start cell's centre and the heading last commanded; else the true one."""
    if p.localisation:
        x, y, th = rb.bx, rb.by, rb.bth
    elif p.open_loop:
        x, y, th = (rb.cell_x + 0.5) * p.cell_m, (rb.cell_y + 0.5) * p.cell_m, rb.bth
    else:
        x, y, th = rb.x, rb.y, rb.th
    leg = plan_leg(x, y, th, rb.tx, rb.ty, rb.head, p.tol_m, p.period, turn_sums, drive_sums,
                   p.tol_rad if p.latency else math.inf)
    rb.nturn, rb.tsign, rb.tscale = leg.nturn, leg.tsign, leg.tscale
    rb.ndrive, rb.dscale, rb.ex, rb.ey, rb.dist = (leg.ndrive, leg.dscale, leg.ex, leg.ey,
                                                   leg.dist)
    rb.cmd = rb.sub = 0
    rb.cmd_set = -1
    rb.nleg = -1
    return leg.nturn > 0 or leg.ndrive > 0


@njit(cache=True, inline="always")
def _rest(rb, p, g, s, depth0):
    """After a step of a resting robot: a step that went deeper into what it rests on is held
    (:func:`_held`), and on a drive it presses the bumper; at ``bumper_travel_m`` the robot
    stays where it was before the step (True: a bump). A step that leaves it touching
    nothing and further than ``bumper_release_m`` from every shape ends the resting."""
    depth1 = depth_at(p, g, s, rb.x, rb.y)
    if depth1 > depth0 + DEEPER_M:
        into = _held(rb, p, g, s)
        if not (rb.nturn > 0 and rb.cmd <= rb.nturn):  # a drive, not a turn in place
            rb.press += into
            if rb.press >= p.bumper_travel_m:
                rb.forced = True
                rb.x, rb.y, rb.th = rb.px, rb.py, rb.pth
                return True
    elif depth1 <= 0.0 and not (p.bumper_release_m > 0.0
                                and within(p, g, s, rb.x, rb.y, p.bumper_release_m)):
        rb.resting = False
    return False


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


@njit(cache=True, inline="always")
def _held(rb, p, g, s):
    """The surface holds the disc: take away the part of the last step that went into it
    (along the surface normal, from central differences of the overlap depth) and return
    how far that was [m] (the bumper's press). As :meth:`PhysicsWorld.hold`."""
    h = HOLD_STEP_M
    x, y = rb.x, rb.y
    gx = depth_at(p, g, s, x + h, y) - depth_at(p, g, s, x - h, y)  # grows into the surface
    gy = depth_at(p, g, s, x, y + h) - depth_at(p, g, s, x, y - h)
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
    plan the next leg from the pose (the estimate with localisation). In open loop the one
    leg's commands are the primitive: done, "reached" as far as the robot knows."""
    if p.open_loop:
        _done(rb, p, reached=True)
    elif at_target(rb.bx if p.localisation else rb.x, rb.by if p.localisation else rb.y,
                   rb.bth if p.localisation else rb.th, rb.tx, rb.ty, rb.head, p.tol_m,
                   p.tol_rad):
        _done(rb, p, reached=True)
    elif rb.steps - rb.steps0 >= p.timeout_steps:
        rb.timeout = True
        _done(rb, p, reached=False)
    else:
        rb.phase = Phase.PLAN


@njit(**BORROWS)
def _bump(rb, p, g, s):
    """A contact began (booked by the caller): the primitive ends with the robot and the
    control body at rest; with carried pose where it is (before the last step when that
    pressed the bumper home), resting; otherwise back on its start cell's centre (above
    ``exact`` resting there if that centre overlaps a shape: noise lets a robot stop within
    tolerance of a centre that is not clear)."""
    rb.vx = rb.vy = rb.w = rb.cvx = rb.cvy = rb.cw = 0.0
    rb.wl = rb.wr = rb.slip_l = rb.slip_r = 0.0  # the bumper stops the motors: nothing
    rb.nsent = 0  # in flight, no slip under way
    rb.bumped = True
    rb.forced = False
    if p.localisation:  # the travel of the period the contact ended
        odometry(rb, p)
    if p.carried_pose:
        rb.resting = True
    else:
        rb.x = (rb.cell_x + 0.5) * p.cell_m
        rb.y = (rb.cell_y + 0.5) * p.cell_m
        rb.resting = ((p.wheel_noise > 0.0 or p.biased or p.open_loop)
                      and depth_at(p, g, s, rb.x, rb.y) > 0.0)
    _done(rb, p, reached=False)


@njit(cache=True)
def _done(rb, p, reached):
    """The primitive ends: its state is the cell the robot believes it is in (the true one
    unless localised); a fix, when one is due, comes first. In open loop without
    localisation the robot believes it faces the heading it was told to take."""
    rb.reached = reached
    ix, iy = cell_of(rb.x, rb.y, p.cell_m, p.nx, p.ny)
    rb.tstate = iy * p.nx + ix
    if p.localisation:
        rb.nfix += 1
        if p.fix_every > 0 and rb.nfix >= p.fix_every:
            rb.bx = rb.x + p.fix_sigma_m * rb.f1
            rb.by = rb.y + p.fix_sigma_m * rb.f2
            rb.bth = rb.th + p.fix_sigma_rad * rb.f3
            rb.nfix = 0
        ix, iy = cell_of(rb.bx, rb.by, p.cell_m, p.nx, p.ny)
    elif p.open_loop:
        rb.bth = rb.head
    rb.state = iy * p.nx + ix
    rb.status = Status.DONE

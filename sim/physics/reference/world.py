"""The Pymunk world of a scenario: walls, obstacles, blocked cells and a diff-drive disc robot.

This is the **reference world**: every physics step is a ``cpSpaceStep``. Driven by
:class:`sim.physics.reference.controller.PrimitiveController` it is the oracle the batched kernel
(:mod:`sim.physics.kernel.primitive`) is tested against at every fidelity; ``DiffDrive`` drives it
directly.

Frames and units as in :mod:`sim.scenario`: metres, seconds, radians, x right,
y up, origin at the arena's bottom-left corner. Top-down: no gravity.

How the robot is driven (Pymunk's ``examples/tank.py``): a kinematic *control
body* carries the commanded twist; a :class:`pymunk.PivotJoint` and a
:class:`pymunk.GearJoint` with ``max_bias = 0`` pull the robot's linear and
angular velocity towards it, each limited by a ``max_force``. Those limits are
the wheels' traction: ``traction_margin`` times what the wheel acceleration
limit needs (``m * a_max`` and ``I * 2 a_max / wheel_base``). A command that
respects the wheel limits is therefore tracked exactly (the robot's velocity
equals the control body's after every step), while a contact the wheels push
against holds. There is no global damping: the ground's friction acts through
the wheels, i.e. through these joints, and the robot is never left undriven.

Why a fresh :class:`pymunk.Space` per world: a copied space does not replay bit
for bit (pymunk#181); a new world per episode does.

Tunnelling: Chipmunk detects contacts only between overlapping shapes after a
step, so a disc at speed ``v`` can enter an obstacle by up to ``v * dt``.
:meth:`PhysicsWorld.cast_free_distance` casts the robot's disc along a straight
leg once; the drive loop then shortens the one step that would cross the first
surface so the disc enters it by at most ``contact_depth_m`` -- enough for
Chipmunk to report the contact, never more: the time-of-impact clamp of a
continuous collision detector, for one query per leg.
:meth:`PhysicsWorld.advance` (free driving, for ``DiffDrive``, and every fidelity above
``exact``) casts every step.

Above ``exact`` (:mod:`sim.physics.fidelity`) a robot at rest against a surface
(:attr:`PhysicsWorld.resting`: carried pose, or placed back on a start centre that overlaps
a shape) is held by the fidelity's rule (:meth:`PhysicsWorld.hold`), not by Chipmunk's
contact impulses: the controller turns :attr:`PhysicsWorld.solve_contacts` off, so contacts
are still detected but take no part in the velocity solve (Chipmunk's own response would
also brake the slide by friction; the rule slides freely).

Hot path: :meth:`PhysicsWorld.drive` calls Chipmunk through pymunk's cffi
``lib`` directly (``cpSpaceStep``, body getters/setters): the public
properties build ``Vec2d`` objects and ``Space.step`` does bookkeeping for
deferred adds/removes and post-step callbacks this world never uses, together
about 3x the cost of the physics itself. If those internals are missing
(another pymunk), the public API is used; both give identical numbers.
"""

from __future__ import annotations

import math
from typing import Any

import pymunk

from sim.physics import sigint
from sim.physics.reference.wheels import WheelState
from sim.physics.static import (
    HOLD_STEP_M,
    STATIC_CATEGORY,
    STATIC_KINDS,
    CollisionType,
    Contact,
    PhysicsConfig,
    SharedSpace,
    contact_of,
    new_space,
    robot_bodies,
    static_shapes,
    sweep_alpha,
)
from sim.scenario import Scenario

try:  # pymunk's own cffi binding of Chipmunk; see the module docstring
    from pymunk._chipmunk_cffi import lib as _cp
except ImportError:  # pragma: no cover - another pymunk layout
    _cp = None


_MISSING = object()


class PhysicsWorld:
    """One episode's Pymunk world. Build a new one per reset (see the module doc).

    Public state: :attr:`space`, :attr:`robot` (dynamic body), :attr:`control`
    (kinematic body), :attr:`steps` (physics steps since built), :attr:`contacts`
    (every contact that began, in order), :attr:`contact_counts`, :attr:`trajectory`
    (the last primitive's: its start pose, then the pose after each step), :attr:`resting`
    (at rest against a surface, see :meth:`hold`) and :attr:`solve_contacts`.
    """

    def __init__(self, scenario: Scenario, config: PhysicsConfig | None = None,
                 pose: tuple[float, float, float] | None = None,
                 cast_cache: dict[tuple[float, ...], float | None] | None = None,
                 shared: SharedSpace | None = None) -> None:
        self.scenario = sc = scenario
        self.config = cfg = config or PhysicsConfig()
        cfg.validate()
        self._h = cfg.dt_s
        self._cast_cache = {} if cast_cache is None else cast_cache
        rb = sc.robot
        self.radius_m = rb.radius_m
        self._shared = shared
        if shared is None:
            space = new_space(cfg)
            space.add(*static_shapes(sc, space.static_body))
        else:  # one robot among others in a Space whose static shapes exist already
            space = shared.space
        self.space = space
        self._query_filter = pymunk.ShapeFilter(mask=STATIC_CATEGORY)

        x, y, th = pose if pose is not None else (*_centre(sc, sc.start), 0.0)
        self._add_robot(x, y, th)
        if shared is None:
            for kind in STATIC_KINDS:
                space.on_collision(CollisionType.ROBOT, kind, begin=self._on_begin, data=kind)
        sigint.install(PhysicsWorld._on_begin)  # Ctrl-C inside a callback is not lost

    def _add_robot(self, x: float, y: float, th: float) -> None:
        """A new robot disc and control body at rest at a pose, joined as in tank.py."""
        robot, shape, control, pivot, gear = robot_bodies(self.scenario, self.config, x, y, th)
        self.space.add(robot, shape, control, pivot, gear)
        if self._shared is not None:
            self._shared.owners[shape] = self
        self.robot, self.robot_shape, self.control = robot, shape, control
        self.pivot, self.gear = pivot, gear
        self.steps = 0
        self.contacts: list[Contact] = []
        self.contact_counts = dict.fromkeys(STATIC_KINDS, 0)
        self.trajectory: list[tuple[float, float, float]] = [(x, y, th)]
        self.resting = False  # at rest against a surface (see hold)
        self.wheels = WheelState()  # latency and slip: what the motors carry (at rest)
        self.solve_contacts = True  # False: contacts take no part in the velocity solve
        self._pending: list[Contact] = []
        self._bind_fast()

    def respawn(self, pose: tuple[float, float, float]) -> None:
        """Start a new episode in this world: a new robot at rest at ``pose``, clocks and
        contacts reset, the static shapes kept.

        Building the static shapes is what a reset costs on a large map (0.04 s for
        3,000 circles, against ~0.02 s for a whole 600-primitive episode); the
        robot's bodies, joints and contact pairs are all new, so an episode replays
        bit for bit like one in a fresh space (tested).
        """
        self.space.remove(self.robot, self.robot_shape, self.control, self.pivot, self.gear)
        if self._shared is not None:
            self._shared.owners.pop(self.robot_shape, None)
        self._add_robot(*pose)

    # ------------------------------------------------------------- pickling
    # The fast path's cffi pointers and functions (see _bind_fast) cannot be pickled;
    # pymunk pickles the Space, bodies, shapes, joints and collision handlers, so a copy
    # (pickle, copy.deepcopy, a worker process) drops them and binds its own. By the time
    # __setstate__ runs the Space in the state is complete (it only refers to this world).
    _UNPICKLABLE = ("_S", "_B", "_C", "_fn")

    def __getstate__(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if k not in self._UNPICKLABLE}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._bind_fast()

    # ------------------------------------------------------------- internals
    def _bind_fast(self) -> None:
        if _cp is not None and hasattr(self.space, "_space") and hasattr(self.robot, "_body"):
            self._S, self._B, self._C = self.space._space, self.robot._body, self.control._body
            self._fn = (_cp.cpSpaceStep, _cp.cpBodySetVelocity, _cp.cpBodySetAngularVelocity,
                        _cp.cpBodyGetPosition, _cp.cpBodyGetAngle, _cp.cpBodyGetVelocity)
        else:  # pragma: no cover - exercised by tests through use_public_api()
            self.use_public_api()

    def use_public_api(self) -> None:
        """Route the hot loop through pymunk's public API (slower; for tests and fallback)."""
        space, robot, control = self.space, self.robot, self.control

        self._S, self._B, self._C = space, robot, control
        self._fn = (lambda _s, dt: space.step(dt),
                    lambda b, v: setattr(b, "velocity", v),
                    lambda b, w: setattr(b, "angular_velocity", w),
                    lambda b: b.position, lambda b: b.angle, lambda b: b.velocity)

    def _on_begin(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, kind: Any) -> None:
        if not self.solve_contacts:
            arbiter.process_collision = False  # until the shapes separate
        self._pending.append(contact_of(-1, kind, arbiter.contact_point_set))

    def _flush_contacts(self) -> None:
        for c in self._pending:
            self.contacts.append(c._replace(step=self.steps))
            self.contact_counts[c.kind] += 1
        self._pending.clear()
        sigint.raise_if_deferred()

    # ------------------------------------------------------------ state
    @property
    def pose(self) -> tuple[float, float, float]:
        """(x [m], y [m], heading [rad]) of the robot; the heading is not wrapped."""
        p = self._fn[3](self._B)
        return (p.x, p.y, self._fn[4](self._B))

    @property
    def velocity(self) -> tuple[float, float, float]:
        """(vx [m/s], vy [m/s], omega [rad/s]) of the robot."""
        v = self.robot.velocity
        return (v.x, v.y, self.robot.angular_velocity)

    @property
    def time_s(self) -> float:
        """Simulated time since the world was built [s]."""
        return self.steps * self._h

    def set_twist(self, vx_m_s: float, vy_m_s: float, omega_rad_s: float) -> None:
        """Command the control body (the robot follows through the joints)."""
        self._fn[1](self._C, (vx_m_s, vy_m_s))
        self._fn[2](self._C, omega_rad_s)

    def touching(self) -> bool:
        """Whether the robot's disc overlaps a wall, an obstacle or a blocked cell now."""
        return any(info.shape.collision_type in STATIC_KINDS
                   for info in self.space.shape_query(self.robot_shape))

    def place(self, x_m: float, y_m: float, heading_rad: float, *,
              resting: bool = False) -> None:
        """Put the robot (and the control body) at rest at a pose; ``resting``: against a
        surface (see :meth:`hold`).

        Only between motions: this is the "return to the start cell" of a
        bumped primitive, not a way of moving the robot. Exact only with
        ``collision_bias = 1`` (see :class:`PhysicsConfig`); otherwise the
        pseudo-velocity of a contact correction still moves the robot in the
        next step.
        """
        for body in (self.robot, self.control):
            body.position, body.angle = (x_m, y_m), heading_rad
            body.velocity, body.angular_velocity = (0.0, 0.0), 0.0
        self.space.reindex_shapes_for_body(self.robot)
        self.resting = resting
        self.wheels = WheelState()  # motors stopped, nothing in flight

    # --------------------------------------------------------- collision queries
    def cast_free_distance(self, x0: float, y0: float, x1: float, y1: float,
                           dist: float) -> tuple[float, float, float, float, float] | None:
        """Guard for a straight leg (x0, y0) -> (x1, y1) of length ``dist`` [m].

        Returns ``None`` when the robot's disc sweeps the whole leg without
        touching anything, else ``(x0, y0, ex, ey, limit)``: along unit
        direction ``e`` the robot may advance ``limit`` = free distance +
        ``contact_depth_m`` from (x0, y0). Shapes the disc already overlaps
        at the start are skipped (see :meth:`cast_alpha`).

        Not ``space.segment_query_first``: Chipmunk's spatial index ignores
        the query radius (Chipmunk2D#138) and misses shapes whose bounding box
        the centre line does not cross. Candidates come from a bounding-box
        query of the swept disc instead, each cast with ``shape.segment_query``.
        Results are memoised in ``cast_cache`` (a pure function of the static
        geometry, so the cache may outlive the world and serve the next one).
        """
        key = (x0, y0, x1, y1)
        free = self._cast_cache.get(key, _MISSING)
        if free is _MISSING:
            alpha = self.cast_alpha(x0, y0, x1, y1)
            free = None if alpha is None else alpha * dist
            self._cast_cache[key] = free
        if free is None:
            return None
        return (x0, y0, (x1 - x0) / dist, (y1 - y0) / dist, free + self.config.contact_depth_m)

    def cast_alpha(self, x0: float, y0: float, x1: float, y1: float) -> float | None:
        """Fraction of (x0, y0) -> (x1, y1) the robot's disc sweeps before touching anything.

        A shape the disc already overlaps at the start is reported by Chipmunk
        at alpha 0 and skipped here: that contact exists, and the solver
        already keeps the robot from moving further into it (skipping it lets
        a robot resting against a wall drive along or away from it).
        """
        return sweep_alpha(self.space, self._query_filter, self.radius_m, x0, y0, x1, y1)

    def overlap_m(self) -> float:
        """Deepest overlap of the robot with static geometry right now [m] (0 if none)."""
        return self.deepest(self.touching_shapes())

    def within_m(self, margin_m: float) -> bool:
        """Whether the robot's disc is closer than ``margin_m`` [m] to any static shape
        (Chipmunk's nearest-point query from its centre)."""
        reach = self.radius_m + margin_m
        info = self.space.point_query_nearest(self.robot.position, reach, self._query_filter)
        return info is not None and info.distance < reach

    def touching_shapes(self) -> list[pymunk.ShapeQueryInfo]:
        """What the robot's disc touches now (Chipmunk's narrow phase, ``cpSpaceShapeQuery``)."""
        return self.space.shape_query(self.robot_shape)

    @staticmethod
    def deepest(infos: list[pymunk.ShapeQueryInfo]) -> float:
        """Deepest overlap among shape-query answers [m] (0 if none)."""
        return max((-p.distance for info in infos for p in info.contact_point_set.points),
                   default=0.0)

    def record_contacts(self, infos: list[pymunk.ShapeQueryInfo]) -> None:
        """Book shape-query answers as contacts that began in the last step."""
        for info in infos:
            c = contact_of(self.steps, info.shape.collision_type, info.contact_point_set)
            self.contacts.append(c)
            self.contact_counts[c.kind] += 1

    def hold(self, x0: float, y0: float) -> float:
        """The carried-pose rule: the surface the robot rests against holds it. The part of
        the last step (from (x0, y0)) that went into the surface, along its normal, is taken
        away; returns how far that was [m]. The normal is the gradient of the deepest overlap
        (central differences, :data:`HOLD_STEP_M` apart, Chipmunk's narrow phase)."""
        body, h = self.robot, HOLD_STEP_M
        x, y = (p := body.position).x, p.y
        d = []
        for px, py in ((x + h, y), (x - h, y), (x, y + h), (x, y - h)):
            body.position = (px, py)
            d.append(self.overlap_m())
        body.position = (x, y)
        gx, gy = d[0] - d[1], d[2] - d[3]  # grows into the surface
        g = math.hypot(gx, gy)
        if g == 0.0:
            return 0.0
        nx, ny = gx / g, gy / g
        into = (x - x0) * nx + (y - y0) * ny
        if into <= 0.0:
            return 0.0
        body.position = (x - into * nx, y - into * ny)
        self.space.reindex_shapes_for_body(body)
        return into

    # ------------------------------------------------------------- stepping
    def drive(self, commands: list[tuple[float, float, float]],
              guard: tuple[float, float, float, float, float] | None,
              trajectory: list[tuple[float, float, float]]) -> bool:
        """Hold each control-body twist ``(vx, vy, omega)`` for one control period.

        Appends the pose after every physics step to ``trajectory``. Stops
        after the step in which a contact began and returns True; returns
        False when all commands were driven. ``guard`` (from
        :meth:`cast_free_distance`) shortens the step that would carry the
        robot past the guard's limit along its direction.
        """
        step, set_vel, set_w, get_pos, get_ang, get_vel = self._fn
        S, B, C = self._S, self._B, self._C
        h, sub = self._h, self.config.substeps
        pending = self._pending
        append = trajectory.append
        last = None
        if guard is None and sub == 1:  # the common case, kept lean
            for n, cmd in enumerate(commands, 1):
                if cmd != last:  # a held command need not be set again
                    set_vel(C, (cmd[0], cmd[1]))
                    set_w(C, cmd[2])
                    last = cmd
                step(S, h)
                p = get_pos(B)
                append((p.x, p.y, get_ang(B)))
                if pending:
                    self.steps += n
                    self._flush_contacts()
                    return True
            self.steps += len(commands)
            return False
        if guard is not None:
            gx, gy, ex, ey, limit = guard
        p = get_pos(B)
        px, py = p.x, p.y
        n = 0
        for cmd in commands:
            if cmd != last:
                set_vel(C, (cmd[0], cmd[1]))
                set_w(C, cmd[2])
                last = cmd
            for _ in range(sub):
                if guard is not None:
                    # position integrates first, with the current velocity: shorten the
                    # step that would carry the disc past the limit
                    v = get_vel(B)
                    done = (px - gx) * ex + (py - gy) * ey
                    if done + h * (v.x * ex + v.y * ey) > limit:
                        u = max(limit - done, 0.0) / h
                        set_vel(B, (u * ex, u * ey))
                step(S, h)
                n += 1
                p = get_pos(B)
                px, py = p.x, p.y
                append((px, py, get_ang(B)))
                if pending:
                    self.steps += n
                    self._flush_contacts()
                    return True
        self.steps += n
        return False

    def advance(self, n_steps: int, trajectory: list[tuple[float, float, float]] | None = None
                ) -> int:
        """Step ``n_steps`` times with the current commands, guarding every step.

        For free driving: each step casts the disc along the displacement the
        step will make (position integrates first, with the current velocity)
        and shortens it as in :meth:`drive`. Contacts do not stop it. Returns
        the number of contacts that began.
        """
        before = len(self.contacts)
        for _ in range(n_steps):
            self.before_step()
            self._fn[0](self._S, self._h)
            self.after_step(trajectory)
        return len(self.contacts) - before

    def step(self, trajectory: list[tuple[float, float, float]] | None = None, *,
             book: bool = True) -> None:
        """One ``cpSpaceStep``: the clock advances, the pose is appended to ``trajectory``;
        contacts that began are booked, or with ``book=False`` dropped (carried pose decides
        them at the pose its rule leaves, see ``PrimitiveController._held_step``)."""
        self._fn[0](self._S, self._h)
        if book:
            self.after_step(trajectory)
        else:
            self.steps += 1
            self._pending.clear()

    def before_step(self) -> None:
        """The time-of-impact clamp of :meth:`advance` for the coming step: casts the disc
        along the displacement the step will make and shortens it to ``contact_depth_m``
        into the first surface."""
        robot, h = self.robot, self._h
        p, v = robot.position, robot.velocity
        length = h * math.hypot(v.x, v.y)
        if length > 1e-12:
            alpha = self.cast_alpha(p.x, p.y, p.x + h * v.x, p.y + h * v.y)
            depth = self.config.contact_depth_m
            if alpha is not None and alpha * length + depth < length:
                robot.velocity = v * ((alpha * length + depth) / length)

    def after_step(self, trajectory: list[tuple[float, float, float]] | None = None) -> None:
        """Book the step this robot's Space just took: clock, trajectory, contacts."""
        self.steps += 1
        if trajectory is not None:
            q = self.robot.position
            trajectory.append((q.x, q.y, self.robot.angle))
        if self._pending:
            self._flush_contacts()


def _centre(sc: Scenario, cell: tuple[int, int]) -> tuple[float, float]:
    return (cell[0] + 0.5) * sc.cell_size_m, (cell[1] + 0.5) * sc.cell_size_m

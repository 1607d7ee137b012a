"""The parts of the physics world around its drive loop: collision types, the config,
contacts, the static shapes, an empty Space (or one shared by several robots' worlds), a
robot's bodies and joints, and the swept-disc query over static shapes.

Split from :mod:`sim.physics.reference.world` (the robot's drive loop) so each file has one job.
Walls are thick segments whose inner surface is the arena boundary; circles are
the scenario's obstacles; blocked map cells become boxes, merged into runs along
each row so a large map adds thousands of shapes, not hundreds of thousands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import Any, NamedTuple

import pymunk

from sim.errors import ScenarioError
from sim.physics import sigint
from sim.scenario import Scenario


class CollisionType(IntEnum):
    """Pymunk collision types of the world's shapes."""

    ROBOT = 1
    OBSTACLE = 2  # circular obstacles
    WALL = 3  # arena walls
    CELL = 4  # blocked map cells


STATIC_KINDS = (CollisionType.OBSTACLE, CollisionType.WALL, CollisionType.CELL)
ROBOT_CATEGORY = 0b01
STATIC_CATEGORY = 0b10
# carried pose (sim.physics.fidelity), the same in the reference world and the kernel:
HOLD_STEP_M = 1e-5  # central-difference step of a surface's normal [m]
DEEPER_M = 1e-12  # a step that deepens the robot's overlap by more pushes into the surface [m]


MAX_FRICTION = 10.0  # a Coulomb coefficient beyond any material pair [-]
MIN_DT_S, MAX_DT_S = 1e-4, 1.0  # a physics step [s]
MAX_SUBSTEPS, MAX_ITERATIONS = 1000, 1000
MAX_TIMEOUT_S = 600.0  # a primitive's give-up time [s]


@dataclass(frozen=True)
class PhysicsConfig:
    """Time stepping, controller tolerances and contact parameters."""

    dt_s: float = 0.1  # physics step [s]
    substeps: int = 1  # physics steps per control period (commands change once per period)
    iterations: int = 10  # Chipmunk solver iterations per step
    tolerance_m: float = 0.02  # a primitive ends this close to the target cell centre [m]
    tolerance_rad: float = math.radians(2.0)  # ... and to the action's cardinal heading [rad]
    timeout_s: float = 5.0  # a primitive gives up after this much simulated time [s]
    #   (checked between legs; a free primitive takes 1.3-2.2 s at the paper robot's limits)
    contact_depth_m: float = 0.005  # deepest a step may carry the robot into a surface [m]
    collision_slop_m: float = 0.001  # overlap Chipmunk leaves uncorrected [m]
    # Fraction of an overlap Chipmunk leaves uncorrected after 1 s [-]. 1.0 = no positional
    # correction: a correction is a pseudo-velocity stored in the body that pymunk cannot
    # clear, so it would move a robot placed back on its start cell after a bump. The
    # time-of-impact clamp bounds every overlap by contact_depth_m instead.
    collision_bias: float = 1.0
    traction_margin: float = 2.0  # joint force limits / what the wheel limits need [-]
    friction: float = 0.5  # robot-to-anything Coulomb friction coefficient [-]

    @property
    def control_period_s(self) -> float:
        """Time one command is held [s]."""
        return self.dt_s * self.substeps

    def validate(self) -> None:
        """Refuse settings that crash Chipmunk or run for minutes: a ScenarioError (a
        ValueError) naming the field, as a scenario file's [physics] table is refused."""
        for name in ("dt_s", "tolerance_m", "tolerance_rad", "timeout_s", "contact_depth_m",
                     "traction_margin"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise _invalid(f"PhysicsConfig.{name} must be a finite positive number, "
                                 f"got {v!r}")
        if not (0.0 <= self.collision_bias <= 1.0):
            raise _invalid(f"PhysicsConfig.collision_bias must be in [0, 1], "
                             f"got {self.collision_bias!r}")
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            raise _invalid(f"PhysicsConfig.substeps must be an int >= 1, got {self.substeps!r}")
        if not (isinstance(self.iterations, int) and self.iterations >= 1):
            raise _invalid(f"PhysicsConfig.iterations must be an int >= 1, "
                             f"got {self.iterations!r}")
        # Chipmunk aborts the interpreter on a nan coefficient; past these bounds a primitive
        # runs for minutes (a step of 1e-9 s, 10^7 substeps), far from any robot's physics
        if not (math.isfinite(self.friction) and 0.0 <= self.friction <= MAX_FRICTION):
            raise _invalid(f"PhysicsConfig.friction must be in [0, {MAX_FRICTION:g}], "
                             f"got {self.friction!r}")
        if not (isinstance(self.collision_slop_m, int | float)
                and math.isfinite(self.collision_slop_m) and self.collision_slop_m >= 0):
            raise _invalid(f"PhysicsConfig.collision_slop_m must be a finite number >= 0, "
                             f"got {self.collision_slop_m!r}")
        if not MIN_DT_S <= self.dt_s <= MAX_DT_S:
            raise _invalid(f"PhysicsConfig.dt_s must be in [{MIN_DT_S:g}, {MAX_DT_S:g}] s, "
                             f"got {self.dt_s!r}")
        if self.substeps > MAX_SUBSTEPS or self.iterations > MAX_ITERATIONS:
            raise _invalid(f"PhysicsConfig.substeps must be at most {MAX_SUBSTEPS} and "
                           f"iterations at most {MAX_ITERATIONS}, got {self.substeps} and "
                           f"{self.iterations}")
        if self.timeout_s > MAX_TIMEOUT_S:
            raise _invalid(f"PhysicsConfig.timeout_s must be at most {MAX_TIMEOUT_S:g} s, "
                             f"got {self.timeout_s!r}")


def _invalid(message: str) -> ScenarioError:
    """``message`` ("PhysicsConfig.<field> must ..., got ...") as the error the CLI prints in
    one line (exit 2) and a Python caller catches as a ValueError."""
    field, _, problem = message.partition(" ")
    return ScenarioError("physics config", field, problem,
                         "use a value in the range given (PhysicsConfig's defaults are a "
                         "small indoor robot)")


class Contact(NamedTuple):
    """A contact that began (Pymunk ``begin``) between the robot and static geometry."""

    step: int  # physics step (since the world was built) in which it began
    kind: CollisionType  # what the robot touched
    x_m: float  # contact point on the robot's surface [m]
    y_m: float
    normal_x: float  # unit normal from the robot towards the other shape
    normal_y: float
    depth_m: float  # overlap when detected [m]


def contact_of(step: int, kind: int, cps: pymunk.ContactPointSet) -> Contact:
    """The :class:`Contact` of a contact point set (an arbiter's, or a shape query's with the
    robot's shape first): its deepest point, the normal, the depth. No point: nan, depth 0."""
    if not cps.points:  # pragma: no cover - Chipmunk always reports a point for these shapes
        return Contact(step, CollisionType(kind), math.nan, math.nan, cps.normal.x,
                       cps.normal.y, 0.0)
    deepest = min(cps.points, key=lambda p: p.distance)
    return Contact(step, CollisionType(kind), deepest.point_a.x, deepest.point_a.y,
                   cps.normal.x, cps.normal.y, -deepest.distance)


def merged_boxes(cells: tuple[tuple[int, int], ...]) -> list[tuple[int, int, int]]:
    """Blocked cells as horizontal runs ``(iy, ix_first, ix_last)``: fewer shapes, same area."""
    runs: list[tuple[int, int, int]] = []
    for iy, ix in sorted((iy, ix) for ix, iy in set(cells)):
        if runs and runs[-1][0] == iy and runs[-1][2] == ix - 1:
            runs[-1] = (iy, runs[-1][1], ix)
        else:
            runs.append((iy, ix, ix))
    return runs


def static_shapes(sc: Scenario, body: pymunk.Body) -> list[pymunk.Shape]:
    """Walls (thick segments whose inner surface is the arena boundary), circles, cell runs."""
    shapes: list[pymunk.Shape] = []
    w, h, t = sc.width_m, sc.height_m, sc.cell_size_m
    for a, b in (((-t, -t), (w + t, -t)), ((w + t, -t), (w + t, h + t)),
                 ((w + t, h + t), (-t, h + t)), ((-t, h + t), (-t, -t))):
        shapes.append(typed(pymunk.Segment(body, a, b, t), CollisionType.WALL))
    for o in sc.obstacles:
        shapes.append(typed(pymunk.Circle(body, o.radius_m, (o.x_m, o.y_m)),
                             CollisionType.OBSTACLE))
    c = sc.cell_size_m
    for iy, ix0, ix1 in merged_boxes(sc.blocked_cells):
        x0, x1, y0, y1 = ix0 * c, (ix1 + 1) * c, iy * c, (iy + 1) * c
        box = pymunk.Poly(body, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
        shapes.append(typed(box, CollisionType.CELL))
    return shapes


def typed(shape: pymunk.Shape, kind: CollisionType) -> pymunk.Shape:
    shape.collision_type = kind
    shape.friction = 1.0  # the robot's friction sets the pair's coefficient (product)
    shape.elasticity = 0.0
    shape.filter = pymunk.ShapeFilter(categories=STATIC_CATEGORY)
    return shape


def new_space(cfg: PhysicsConfig) -> pymunk.Space:
    """An empty top-down Space with the config's solver and contact settings."""
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    space.damping = 1.0
    space.iterations = cfg.iterations
    space.collision_slop = cfg.collision_slop_m
    space.collision_bias = cfg.collision_bias
    return space


def sweep_alpha(space: pymunk.Space, query_filter: pymunk.ShapeFilter, radius_m: float,
                x0: float, y0: float, x1: float, y1: float) -> float | None:
    """Fraction of (x0, y0) -> (x1, y1) a disc of ``radius_m`` sweeps before touching a shape
    that ``query_filter`` lets through; None if it touches none. See
    :meth:`sim.physics.reference.world.PhysicsWorld.cast_alpha` (one implementation for every
    world)."""
    r = radius_m
    bb = pymunk.BB(min(x0, x1) - r, min(y0, y1) - r, max(x0, x1) + r, max(y0, y1) + r)
    alpha = math.inf
    for shape in space.bb_query(bb, query_filter):
        info = shape.segment_query((x0, y0), (x1, y1), r)
        if info is not None and 0.0 < info.alpha < alpha:
            alpha = info.alpha
    return None if alpha == math.inf else alpha


def robot_bodies(sc: Scenario, cfg: PhysicsConfig, x: float, y: float, th: float
                 ) -> tuple[pymunk.Body, pymunk.Circle, pymunk.Body, pymunk.PivotJoint,
                            pymunk.GearJoint]:
    """A robot disc and its control body at rest at a pose, joined as in pymunk's tank.py:
    (body, shape, control body, pivot joint, gear joint), not yet in a Space. The shape is
    filtered to touch static geometry only (robots in one Space never touch)."""
    rb = sc.robot
    moment = pymunk.moment_for_circle(rb.mass_kg, 0.0, rb.radius_m)
    robot = pymunk.Body(rb.mass_kg, moment)
    robot.position, robot.angle = (x, y), th
    shape = pymunk.Circle(robot, rb.radius_m)
    shape.collision_type = CollisionType.ROBOT
    shape.friction = cfg.friction
    shape.elasticity = 0.0
    shape.filter = pymunk.ShapeFilter(categories=ROBOT_CATEGORY, mask=STATIC_CATEGORY)
    control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    control.position, control.angle = (x, y), th
    pivot = pymunk.PivotJoint(control, robot, (0.0, 0.0), (0.0, 0.0))
    pivot.max_bias = 0.0  # match velocities only; positions are the controller's job
    pivot.max_force = cfg.traction_margin * rb.mass_kg * rb.max_wheel_accel_m_s2
    gear = pymunk.GearJoint(control, robot, 0.0, 1.0)
    gear.max_bias = 0.0
    gear.max_force = (cfg.traction_margin * moment * 2.0 * rb.max_wheel_accel_m_s2
                      / rb.wheel_base_m)
    return robot, shape, control, pivot, gear


class SharedSpace:
    """One ``pymunk.Space`` with a scenario's static shapes, for several robots' worlds.

    Each :class:`sim.physics.reference.world.PhysicsWorld` built with ``shared=`` adds its
    robot here
    (robots are filtered so they never touch each other) and gets the contacts its own shape
    begins; :meth:`step` advances all of them at once (DiffDrive's vector env).
    """

    def __init__(self, scenario: Scenario, config: PhysicsConfig) -> None:
        config.validate()
        self.space = new_space(config)
        self.space.add(*static_shapes(scenario, self.space.static_body))
        self.owners: dict[pymunk.Shape, Any] = {}  # shape -> its PhysicsWorld
        for kind in STATIC_KINDS:
            self.space.on_collision(CollisionType.ROBOT, kind, begin=self._on_begin, data=kind)
        sigint.install(SharedSpace._on_begin)

    def _on_begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, kind: Any) -> None:
        a, b = arbiter.shapes
        owner = self.owners.get(a) or self.owners.get(b)
        if owner is not None:
            owner._on_begin(arbiter, space, kind)

    def step(self, dt_s: float) -> None:
        self.space.step(dt_s)

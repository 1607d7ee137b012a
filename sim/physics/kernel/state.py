"""The batched kernel's state by name (:mod:`sim.physics.kernel.primitive`).

Each robot is a record of :data:`ROBOT` (in compiled code ``rb = robots[i]``, a reference:
``rb.x``; in Python :func:`by_name` gives a :class:`Robots` of 1-D views, ``r.x[i]``). A
batch's constants are one :class:`Params` (numbers only), its tables
:class:`sim.physics.drive_profiles.Profiles` and :class:`Geometry`, its caches :class:`Scratch`.

Not a NamedTuple of arrays for the robots: numba types a NamedTuple argument by its slow path
on every call (10-14 us for fifty arrays, measured; a record array 0.4 us), and a batch of one
makes a call per primitive (~28 us); the tuples cross as plain tuples, rebuilt inside
(``Params(*pt)``). Arrays stay out of the per-step helpers: numba increfs and decrefs every
array of every tuple argument at each call (13 arrays per step took the kernel from 0.5 to
2.4 us per primitive).
"""

from __future__ import annotations

import dataclasses
import typing
from enum import IntEnum
from typing import NamedTuple

import numpy as np

from sim.physics.fidelity import (
    MAX_DELAY_PERIODS,
    Fidelity,
    delay_periods,
    lag_keep,
    slip_start_probability,
)

__all__ = ["BORROWS", "FIDELITY_KNOBS", "ROBOT", "Geometry", "Params", "Phase", "Robots",
           "Scratch", "Status", "by_name", "params_of"]

# numba options of the kernel's compiled helpers that only read and write the arrays they are
# handed (they allocate nothing, keep nothing): no reference counting. numba otherwise takes
# and drops a reference to every array argument (and each array of a tuple argument) at
# each call, an atomic operation each: 26 at each call of a primitive's loop, eight at
# each query of the shapes. The caller holds the arrays for the call's whole length.
BORROWS = dict(cache=True, _nrt=False)


class Status(IntEnum):
    """Where a robot's primitive stands between calls of
    :func:`sim.physics.kernel.primitive.advance`."""

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
    ("phase", _I),  # the leg (a sim.physics.reference.controller.Leg), where it stands, its guard:
    ("nturn", _I), ("tsign", _F), ("tscale", _F), ("ndrive", _I), ("dscale", _F), ("ex", _F),
    ("ey", _F), ("dist", _F),
    ("cmd", _I), ("sub", _I), ("cmd_set", _I),  # command and substep now; command in cv*
    ("gx", _F), ("gy", _F), ("limit", _F), ("free", _F),  # leg guard: start, allowance, free
    # the fidelity's per-run bias (sim.physics.fidelity): each wheel's delivered fraction of
    # its command, and the true wheelbase over the nominal one (1, 1, 1: none)
    ("gain_l", _F), ("gain_r", _F), ("base_k", _F),
    # what the robot believes (open loop, localisation): its pose estimate [m, m, rad]; the
    # wheels' travel [m] and yaw [rad] this control period (odometry); the period's odometry
    # normals; the fix's normals (reserved when the primitive starts); primitives since the
    # last fix; the true cell (state: the believed one); a primitive not yet begun
    ("bx", _F), ("by", _F), ("bth", _F), ("odo_d", _F), ("odo_th", _F),
    ("o1", _F), ("o2", _F), ("o3", _F), ("f1", _F), ("f2", _F), ("f3", _F),
    ("nfix", _I), ("tstate", _I), ("fresh", _B),
    # a ball the disc's centre may roam without coming near any static shape (above exact:
    # steps inside it need no sweep; sim.physics.kernel.queries.new_clear_region) [m];
    # radius <= 0: none
    ("clear_x", _F), ("clear_y", _F), ("clear_r", _F),
    # ... and an axis-aligned box of the same kind (x0, y0, x1, y1; empty: x1 <= x0), which
    # reaches along a corridor where the ball stops at its walls [m]
    ("box_x0", _F), ("box_y0", _F), ("box_x1", _F), ("box_y1", _F),
    # latency and slip (sim.physics.fidelity): each wheel's lagged speed [m/s]; the wheel
    # commands sent, a ring of the last SENT_RING (left, right) [m/s], and how many were
    # sent since the motors last stopped; each wheel's slip time left [s]
    ("wl", _F), ("wr", _F), ("sent", _F, (MAX_DELAY_PERIODS + 1, 2)), ("nsent", _I),
    ("slip_l", _F), ("slip_r", _F),
    ("nleg", _I),  # latency: the leg's command count, once its commands are driven (-1)
], align=True)
SENT_RING = MAX_DELAY_PERIODS + 1  # a command sent MAX_DELAY_PERIODS ago is still kept

# Python's view: every field of ROBOT as a 1-D array of length N (views into the records)
Robots = NamedTuple("Robots", [(name, np.ndarray) for name in ROBOT.names])  # type: ignore[misc]


def by_name(robots: np.ndarray) -> Robots:
    """``robots`` (records of :data:`ROBOT`) as a :class:`Robots` of views: ``r.x[i]``."""
    return Robots(*(robots[name] for name in ROBOT.names))




# A batch's constants (scenario, PhysicsConfig, fidelity), numbers only: the drive's own,
# then ``biased`` (a per-run wheel bias is drawn: the robots' gain_l, gain_r, base_k), then
# every knob of :class:`~sim.physics.fidelity.Fidelity` under its own name and type, read
# from the dataclass: a new knob reaches the kernel as ``p.<knob>`` with no line here.
_DRIVE_FIELDS = [
    ("dt", float),  # physics step [s]
    ("substeps", int),  # physics steps per control period (of `period` [s])
    ("period", float),
    ("tol_m", float),  # a primitive ends this close to the target centre [m]
    ("tol_rad", float),  # ... and to its heading [rad]
    ("timeout_steps", int),  # a primitive gives up after this many steps (checked between legs)
    ("depth_m", float),  # deepest a guarded step carries the disc into a surface [m]
    ("dv_max", float),  # the pivot joint's impulse limit per step, as a speed change [m/s]
    ("dw_max", float),  # the gear joint's, as a yaw-rate change [rad/s]
    ("cell_m", float),  # cell size [m]
    ("nx", int),  # grid width [cells]
    ("ny", int),  # grid height [cells]
    ("radius_m", float),  # robot radius [m]
    ("wheel_base_m", float),  # [m]
    ("biased", bool),  # fidelity: a per-run wheel bias is drawn
    ("latency", bool),  # fidelity: the wheels lag or get their commands late
    ("lag_keep", float),  # ... the part of a wheel's speed error left after a period [-]
    ("delay", int),  # ... commands reach the wheels this many control periods late
    ("slips", bool),  # fidelity: slip events are drawn
    ("slip_p", float),  # ... the chance a wheel starts a slip in a control period [-]
]
_KNOB_TYPES = typing.get_type_hints(Fidelity)
FIDELITY_KNOBS = tuple(f.name for f in dataclasses.fields(Fidelity) if f.name != "name")
Params = NamedTuple("Params", [*_DRIVE_FIELDS,  # type: ignore[misc]
                               *((k, _KNOB_TYPES[k]) for k in FIDELITY_KNOBS)])


def params_of(fidelity: Fidelity, **drive: float | int) -> Params:
    """The kernel's constants: the drive's (``drive``, by name) and the fidelity's knobs,
    each under its own name."""
    period = float(drive["period"])
    return Params(**drive, biased=fidelity.biased, latency=fidelity.latency,
                  lag_keep=lag_keep(fidelity, period), delay=delay_periods(fidelity, period),
                  slips=fidelity.slips, slip_p=slip_start_probability(fidelity, period),
                  **{k: getattr(fidelity, k) for k in FIDELITY_KNOBS})


class Geometry(NamedTuple):
    """The static shapes as arrays (:class:`sim.physics.kernel.sweep.StaticGeometry`)."""

    circles: np.ndarray
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

"""N diff-drive robots in one ``pymunk.Space``, each driving grid primitives.

The static shapes (walls, circles, blocked cells) are built once and shared. Each robot
has its own dynamic disc, kinematic control body, pivot and gear joint (as in
:mod:`sim.physics.reference.world`), its own controller state, contacts and episode; robot shapes
carry ``ShapeFilter(categories=ROBOT, mask=STATIC)``, so robots never touch each other.

A batched step (:meth:`RouteBatch.step`) runs every active robot's primitive in one
compiled call (:func:`sim.physics.kernel.primitive.advance`: free motion integrated as Chipmunk
integrates it, see that module for why it is the same physics). Swept-disc guards are
cast in that call too, with Chipmunk's segment-query formulas over the static shapes as
arrays (:mod:`sim.physics.kernel.sweep`); at ``exact`` a leg that starts on its cell centre has a
fixed answer per (cell, action), cached in :attr:`RouteBatch.guards`. Where a step ends at
or past a guard's surface (or presses the bumper home), Chipmunk's narrow phase (the
collision detection ``cpSpaceStep`` and ``shape_query`` run), written out in compiled code
(:mod:`sim.physics.kernel.narrow_phase`), says whether a contact began and where; if so the
primitive ends as in the reference world. Chipmunk itself is asked (``CHECK``,
:meth:`RouteBatch._check`) only where that code cannot be sure of Chipmunk's answer: a box
within rounding of touching.

A robot in a batch is the reference world (:class:`sim.physics.reference.world.PhysicsWorld` driven
by :class:`sim.physics.reference.controller.PrimitiveController`) at every fidelity: the same cells,
bumps, contacts and step counts for the same actions and noise seed, poses within 1e-9 m
(tested on two maps at ``exact``, wheel noise only and ``noisy``), and independent of which
other robots share the batch (robots are processed one by one in index order, and the
guard cache holds answers that do not depend on who asked).
"""

from __future__ import annotations

import math
import time

import numpy as np
import pymunk

from sim.grid.discretiser import Discretiser
from sim.physics import sigint
from sim.physics.drive_profiles import DriveLimits, profiles
from sim.physics.fidelity import Fidelity
from sim.physics.generator_handle import HANDLE_SIZE, handle
from sim.physics.kernel import primitive as K
from sim.physics.kernel.narrow_phase import contact_buffer
from sim.physics.kernel.noise import refill_one
from sim.physics.kernel.readouts import outcome, path_lengths
from sim.physics.kernel.state import ROBOT, Geometry, Scratch, Status, by_name, params_of
from sim.physics.kernel.sweep import static_geometry
from sim.physics.motion import PrimitiveOutcome
from sim.physics.static import (
    STATIC_CATEGORY,
    CollisionType,
    Contact,
    PhysicsConfig,
    contact_of,
    new_space,
    robot_bodies,
    static_shapes,
)
from sim.scenario import Scenario

NOISE_BLOCK = 4096  # normals drawn per refill of a robot's wheel-noise buffer (at most)
FIRST_NOISE_BLOCK = 256  # ... the first refill of a new stream (then doubling)
_BLANK = np.zeros((), ROBOT)
_KIND_OF = {int(k): k for k in CollisionType}
_DONE, _NOISE, _CHECK, _CONTACT = (int(c) for c in (Status.DONE, Status.NOISE, Status.CHECK,
                                                     Status.CONTACT))


class RouteBatch:
    """N robots in one Space, each driving grid actions as motion primitives.

    :attr:`robots` is every robot's state, records of :data:`sim.physics.kernel.state.ROBOT`;
    :attr:`r` the same by name, a :class:`sim.physics.kernel.state.Robots` of 1-D views
    (``r.x[i]``). ``guards`` may be shared between batches of one
    scenario and config (a pure function of the static geometry). ``trajectories=True``
    keeps the pose after every physics step of the last primitive (:meth:`trajectory`), as
    the env's ``info`` wants. ``contact_records=False`` keeps no :attr:`contacts` (each
    robot's list stays empty; ``contact_counts`` stay zero) but still counts each
    primitive's contacts in its outcome: a batch that only needs the counts (rollouts,
    training) builds no record per contact.
    """

    def __init__(self, scenario: Scenario, n_robots: int, config: PhysicsConfig | None = None,
                 *, trajectories: bool = False, guards: np.ndarray | None = None,
                 fidelity: Fidelity | None = None, contact_records: bool = True) -> None:
        if not (isinstance(n_robots, int) and n_robots >= 1):
            raise ValueError(f"n_robots must be an int >= 1, got {n_robots!r}")
        self.scenario = sc = scenario
        self.config = cfg = config or PhysicsConfig()
        cfg.validate()
        self.fidelity = fid = fidelity or Fidelity()
        fid.validate()
        self.n = n_robots
        self.disc = disc = Discretiser.from_scenario(sc)
        self.nx, self.ny = disc.nx, disc.ny
        self.cell_m = sc.cell_size_m
        self.radius_m = sc.robot.radius_m
        space = new_space(cfg)
        space.add(*static_shapes(sc, space.static_body))
        self.space = space
        self._query_filter = pymunk.ShapeFilter(mask=STATIC_CATEGORY)
        self.bodies: list[pymunk.Body] = []
        self.shapes: list[pymunk.Circle] = []
        x0, y0 = disc.cell_centre(*sc.start)
        for _ in range(n_robots):
            self._add_robot(x0, y0)
        # the kernel's constants: the same tables and rules as PrimitiveController
        lim = DriveLimits.from_robot(sc.robot)
        prof = profiles(lim, cfg.control_period_s, self.cell_m)
        timeout_steps = math.ceil(cfg.timeout_s / cfg.dt_s - 1e-9)
        self.geometry = g = static_geometry(sc)
        pivot, gear = robot_bodies(sc, cfg, x0, y0, 0.0)[3:]  # the joints' force limits
        body = self.bodies[0]
        self.params = params_of(
            fid, dt=cfg.dt_s, substeps=cfg.substeps, period=cfg.control_period_s,
            tol_m=cfg.tolerance_m, tol_rad=cfg.tolerance_rad, timeout_steps=timeout_steps,
            depth_m=cfg.contact_depth_m, dv_max=pivot.max_force * cfg.dt_s / body.mass,
            dw_max=gear.max_force * cfg.dt_s / body.moment, cell_m=self.cell_m, nx=self.nx,
            ny=self.ny, radius_m=self.radius_m, wheel_base_m=lim.wheel_base_m)
        self.profiles = prof
        self.static = Geometry(g.circles, g.walls, g.boxes, g.start, g.items)
        n_s = self.nx * self.ny
        if guards is None:
            guards = np.full((n_s, 4), np.nan)
        elif guards.shape != (n_s, 4):
            raise ValueError(f"guards must have shape {(n_s, 4)}, got {guards.shape}")
        self.guards = guards
        self.scratch = Scratch(guards, np.zeros(len(g.circles) + len(g.boxes), np.int64),
                                 np.zeros(2, np.int64))
        # numba types plain tuples fast, NamedTuples slowly (see sim.physics.kernel.primitive)
        self._args = (tuple(self.params), tuple(prof), tuple(self.static), tuple(self.scratch))
        self.robots = np.zeros(n_robots, ROBOT)
        self.r = by_name(self.robots)
        # each robot's per-run bias (gain_l, gain_r, base_k): drawn by set_noise_rng
        self._bias = np.ones((n_robots, 3))
        for i in range(n_robots):
            self._blank(i, x0, y0, 0.0)
        cap = (timeout_steps + 2 * (prof.drive_sums.size + prof.turn_sums.size) + 8
               if trajectories else 0)
        self._traj = np.zeros((n_robots, cap, 3))
        self._traj_start = np.zeros((n_robots, 3))
        self._all = np.ones(n_robots, dtype=np.bool_)
        self.contacts: list[list[Contact]] = [[] for _ in range(n_robots)]
        self.contact_counts = [dict.fromkeys(CollisionType, 0) for _ in range(n_robots)]
        self._booked_rows = contact_buffer(n_robots)  # contacts the kernel found ...
        self._booked = np.zeros(n_robots, np.int64)  # ... how many, per robot
        self.contact_records = contact_records
        self.checks = 0  # Chipmunk contact checks so far (benchmark figures)
        self.kernel_s = 0.0  # wall time in the compiled kernel so far [s]
        self.chipmunk_s = 0.0  # wall time in Chipmunk contact checks so far [s]
        # each robot's normals for wheel noise, drawn in blocks from its own generator
        self._noise = np.zeros((n_robots, NOISE_BLOCK if fid.wheel_noise > 0
                                              or fid.localisation or fid.slips else 2))
        self._npos = np.full(n_robots, self._noise.shape[1], dtype=np.int64)  # next normal
        self._nend = self._npos.copy()  # end of the normals drawn so far in the block
        self._nblock = np.full(n_robots, FIRST_NOISE_BLOCK, dtype=np.int64)
        self._noise_rngs: list[np.random.Generator | None] = [None] * n_robots
        self._noise_h = np.zeros((n_robots, HANDLE_SIZE), np.uint64)  # their handles
        sigint.install(RouteBatch._check)

    def _add_robot(self, x: float, y: float) -> None:
        body, shape, control, pivot, gear = robot_bodies(self.scenario, self.config, x, y, 0.0)
        self.space.add(body, shape, control, pivot, gear)
        self.bodies.append(body)
        self.shapes.append(shape)

    # ------------------------------------------------------------------ pickling
    # ``r`` holds views into ``robots``; pickle (and copy.deepcopy) would turn them into
    # arrays of their own, and the kernel's writes to ``robots`` would no longer show in
    # ``r`` (a copied env would diverge from its original). The copy rebuilds them, and
    # its generator handles.
    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k != "r"}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self.r = by_name(self.robots)
        # a generator handle is the address of its generator's state: the copy's handles
        # must name the copy's generators, not the original's (they would draw from those)
        self._noise_h = np.zeros_like(self._noise_h)
        for i, rng in enumerate(self._noise_rngs):
            if rng is not None:
                self._noise_h[i] = handle(rng)

    # ------------------------------------------------------------------ episodes
    def place(self, i: int, x_m: float, y_m: float, heading_rad: float = 0.0, *,
              resting: bool = False) -> None:
        """Put robot ``i`` at rest at a pose: a new episode (its step clock and contacts
        reset); ``resting``: against a surface (as ``PhysicsWorld.place``)."""
        r = self.r
        self._blank(i, x_m, y_m, heading_rad)
        r.resting[i] = resting
        self.contacts[i] = []
        self.contact_counts[i] = dict.fromkeys(CollisionType, 0)
        self._booked[i] = 0
        # (the robot's pymunk body is moved only when Chipmunk is asked: sync_body)

    def place_many(self, robots: np.ndarray, x_m: np.ndarray, y_m: np.ndarray,
                   heading_rad: np.ndarray, resting: np.ndarray | bool = False) -> None:
        """:meth:`place` for each robot of ``robots`` (distinct indices) at once: the same
        records, array operations instead of a Python call per robot (a V* model places
        hundreds of thousands)."""
        idx = np.asarray(robots, dtype=np.int64)
        r = self.r
        self.robots[idx] = _BLANK
        r.x[idx], r.y[idx], r.th[idx] = x_m, y_m, heading_rad
        r.bx[idx], r.by[idx], r.bth[idx] = x_m, y_m, heading_rad
        bias = self._bias[idx]
        r.gain_l[idx], r.gain_r[idx], r.base_k[idx] = bias[:, 0], bias[:, 1], bias[:, 2]
        r.resting[idx] = resting
        self._booked[idx] = 0
        if self.contact_records:
            for i in idx.tolist():
                self.contacts[i] = []
                self.contact_counts[i] = dict.fromkeys(CollisionType, 0)

    def _blank(self, i: int, x_m: float, y_m: float, heading_rad: float) -> None:
        """Robot ``i``'s record all new at a pose, which it knows (its estimate is the pose:
        placed by hand), keeping its per-run bias."""
        r = self.r
        self.robots[i] = _BLANK
        r.x[i], r.y[i], r.th[i] = x_m, y_m, heading_rad
        r.bx[i], r.by[i], r.bth[i] = x_m, y_m, heading_rad
        r.gain_l[i], r.gain_r[i], r.base_k[i] = self._bias[i]

    def believed_pose(self, i: int) -> tuple[float, float, float]:
        """What robot ``i`` believes its pose is (with localisation: its estimate; in open loop
        without it: the heading is the one last commanded; otherwise the true pose)."""
        r, fid = self.r, self.fidelity
        if fid.localisation:
            return float(r.bx[i]), float(r.by[i]), float(r.bth[i])
        if fid.open_loop:
            return float(r.x[i]), float(r.y[i]), float(r.bth[i])
        return self.pose(i)

    def bias(self, i: int) -> tuple[float, float, float]:
        """Robot ``i``'s per-run bias: left and right wheel gains, true over nominal
        wheelbase (1, 1, 1 without one)."""
        return tuple(float(v) for v in self._bias[i])  # type: ignore[return-value]

    def pose(self, i: int) -> tuple[float, float, float]:
        """(x [m], y [m], heading [rad], not wrapped) of robot ``i``."""
        r = self.r
        return float(r.x[i]), float(r.y[i]), float(r.th[i])

    def poses(self) -> np.ndarray:
        """float64[N, 3]: every robot's (x [m], y [m], heading [rad], not wrapped)."""
        r = self.r
        return np.stack([r.x, r.y, r.th], axis=1)

    def steps(self, i: int) -> int:
        """Physics steps robot ``i`` has driven since it was placed."""
        return int(self.r.steps[i])

    def time_s(self, i: int) -> float:
        return self.steps(i) * self.config.dt_s

    @property
    def records_trajectories(self) -> bool:
        """Whether each primitive's poses are kept for :meth:`trajectory` (built with
        ``trajectories=True``)."""
        return bool(self._traj.shape[1])

    def trajectory(self, i: int) -> np.ndarray:
        """float64[n, 3]: robot ``i``'s pose before its last primitive, then after each step."""
        n = int(self.r.ntraj[i])
        return np.concatenate([self._traj_start[i][None], self._traj[i, :n]])

    def primitive_metres(self) -> np.ndarray:
        """float64[n_robots]: the path length of each robot's last primitive [m], the sum of
        its steps' lengths (:meth:`trajectory`'s), for every robot in one call: a loop over
        robots in Python was most of a graded drive's time."""
        out = np.zeros(self._traj_start.shape[0])
        path_lengths(self._traj_start, self._traj, self.r.ntraj, out)
        return out

    def sync_body(self, i: int) -> pymunk.Body:
        """Robot ``i``'s body in the Space, moved to the robot's pose (for queries, drawing)."""
        body, r = self.bodies[i], self.r
        body.position = (float(r.x[i]), float(r.y[i]))
        body.angle = float(r.th[i])
        self.space.reindex_shapes_for_body(body)
        return body

    def overlap_m(self, i: int) -> float:
        """Deepest overlap of robot ``i`` with static geometry now [m] (0 if none)."""
        self.sync_body(i)
        worst = 0.0
        for info in self.space.shape_query(self.shapes[i]):
            for p in info.contact_point_set.points:
                worst = max(worst, -p.distance)
        return worst

    # ------------------------------------------------------------------ stepping
    def step(self, actions: np.ndarray, active: np.ndarray | None = None) -> PrimitiveOutcome:
        """Drive ``actions[i]`` for every robot ``i`` with ``active[i]`` (default: all)."""
        act = self._all if active is None else np.asarray(active, dtype=np.bool_)
        acts = np.asarray(actions, dtype=np.int64)
        rb, r = self.robots, self.r
        if self.records_trajectories:
            self._traj_start[:] = self.poses()
        K.begin_all(rb, acts, act, self.cell_m, self.nx, self.ny, self.fidelity.localisation)
        clock = time.perf_counter
        while True:
            t0 = clock()
            n_waiting = K.advance(rb, self._noise, self._npos, self._nend, self._traj,
                                  self._booked_rows, self._booked, *self._args, act)
            t1 = clock()
            self.kernel_s += t1 - t0
            if n_waiting == 0:
                if self.contact_records and self._booked.any():
                    self._book()  # (without records, the counts are the outcome's)
                sigint.raise_if_deferred()  # one deferred while the world was built, too
                break
            status = r.status
            for i in np.flatnonzero(act & (status != _DONE)):
                if status[i] == _NOISE:
                    self._refill(int(i))
                elif status[i] == _CHECK:
                    self._check(int(i))
            self.chipmunk_s += clock() - t1
            sigint.raise_if_deferred()
        return PrimitiveOutcome(*outcome(rb, act))

    @property
    def casts(self) -> int:
        """Guard casts so far (legs whose guard was not cached)."""
        return int(self.scratch.counters[1])

    def set_noise_rng(self, i: int, rng: np.random.Generator) -> None:
        """Robot ``i``'s wheel noise comes from ``rng`` from now on (its buffer is emptied): a
        new run. With a per-run bias (:attr:`Fidelity.biased`) the robot's E_d and E_b are
        drawn first, two normals of ``rng``: a new robot."""
        self._noise_rngs[i] = rng  # (kept alive: its handle does not own it)
        self._noise_h[i] = handle(rng)
        self._npos[i] = self._nend[i] = self._noise.shape[1]
        self._nblock[i] = FIRST_NOISE_BLOCK
        fid = self.fidelity
        if fid.biased:
            e_d, e_b = rng.standard_normal(2)
            ratio = 1.0 + fid.wheel_ratio_sigma * e_d  # right over left wheel diameter
            self._bias[i] = (2.0 / (ratio + 1.0), 2.0 * ratio / (ratio + 1.0),
                             1.0 + fid.wheelbase_sigma * e_b)
            r = self.r
            r.gain_l[i], r.gain_r[i], r.base_k[i] = self._bias[i]

    def _refill(self, i: int) -> None:
        """Robot ``i``'s next normals, in its stream's block layout
        (:mod:`sim.physics.kernel.noise`)."""
        if self._noise_rngs[i] is None:
            raise RuntimeError(f"robot {i} has wheel noise but no generator: call "
                               "set_noise_rng(i, rng) first")
        refill_one(i, self._noise, self._npos, self._nend, self._nblock, self._noise_h)

    def _book(self) -> None:
        """The contacts the kernel's narrow phase found, into each robot's records."""
        rows = self._booked_rows
        for i in np.flatnonzero(self._booked):
            for c in rows[i, :self._booked[i]].tolist():
                contact = Contact(int(c[0]), _KIND_OF[int(c[1])], *c[2:])
                self.contacts[i].append(contact)
                self.contact_counts[i][contact.kind] += 1
        self._booked[:] = 0

    def _check(self, i: int) -> None:
        """Did a contact begin in robot ``i``'s last step? Chipmunk's narrow phase decides: a
        shape the disc touches now and did not touch before the step (when it rested against
        one); or, when the step pressed the bumper home, whatever it rests against."""
        self.checks += 1
        r = self.r
        shape = self.shapes[i]
        forced = bool(r.forced[i])
        self.sync_body(i)
        found = self.space.shape_query(shape)
        if not forced and r.resting[i] and found:
            # resting contacts are not new ones: only shapes it did not touch before the step
            body = self.bodies[i]
            body.position, body.angle = (float(r.px[i]), float(r.py[i])), 0.0
            self.space.reindex_shapes_for_body(body)
            before = {info.shape for info in self.space.shape_query(shape)}
            self.sync_body(i)
            found = [info for info in found if info.shape not in before]
        if not found and not forced:
            return  # still CHECK: the kernel finishes the step
        step = int(r.steps[i])
        for info in found if self.contact_records else ():
            c = contact_of(step, info.shape.collision_type, info.contact_point_set)
            self.contacts[i].append(c)
            self.contact_counts[i][c.kind] += 1
        r.ncontact[i] += len(found)
        r.status[i] = _CONTACT  # the kernel ends the primitive in a bump


class RobotView:
    """One robot of a :class:`RouteBatch`, read like a
    :class:`sim.physics.reference.world.PhysicsWorld`
    (``pose``, ``steps``, ``time_s``, ``contacts``, ``contact_counts``, ``overlap_m()``)."""

    def __init__(self, batch: RouteBatch, index: int) -> None:
        self.batch, self.index = batch, index

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.batch.pose(self.index)

    @property
    def steps(self) -> int:
        return self.batch.steps(self.index)

    @property
    def time_s(self) -> float:
        return self.batch.time_s(self.index)

    @property
    def contacts(self) -> list[Contact]:
        return self.batch.contacts[self.index]

    @property
    def contact_counts(self) -> dict[CollisionType, int]:
        return self.batch.contact_counts[self.index]

    def overlap_m(self) -> float:
        return self.batch.overlap_m(self.index)

"""N diff-drive robots in one ``pymunk.Space``, each driving grid primitives.

The static shapes (walls, circles, blocked cells) are built once and shared. Each robot
has its own dynamic disc, kinematic control body, pivot and gear joint (as in
:mod:`sim.physics.world`), its own controller state, contacts and episode; robot shapes
carry ``ShapeFilter(categories=ROBOT, mask=STATIC)``, so robots never touch each other.

A batched step (:meth:`RouteBatch.step`) runs every active robot's primitive in one
compiled call (:func:`sim.physics.kernel.advance`: free motion integrated as Chipmunk
integrates it, see that module for why it is the same physics). A drive leg's swept-disc
guard is cast in that call too, with Chipmunk's segment-query formulas over the static
shapes as arrays (:mod:`sim.physics.sweep`); a leg that starts on its cell centre has a
fixed answer per (cell, action), cached in :attr:`RouteBatch.guards`. Chipmunk itself is
asked only at ``CHECK``: a step that ends at or past the guard's surface; the robot's own
shape is put at the new pose and Chipmunk's collision detection (``shape_query``, the
narrow phase ``cpSpaceStep`` runs) says whether a contact began and where; if so the robot
is placed back at rest on its start cell's centre, as in the single world.

A robot in a batch is the single-robot world: the same cells, rewards, contacts and
step counts for the same actions, poses within 1e-9 m of
:class:`sim.physics.world.PhysicsWorld` (tested on two maps, bumps included), and
independent of which other robots share the batch (robots are processed one by one
in index order, and the guard cache holds answers that do not depend on who asked).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pymunk

from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS
from sim.grid.discretiser import Discretiser
from sim.physics import kernel as K
from sim.physics import sigint
from sim.physics.controller import DriveLimits, ProfileTable
from sim.physics.fidelity import Fidelity
from sim.physics.static import (
    STATIC_CATEGORY,
    CollisionType,
    Contact,
    PhysicsConfig,
    static_shapes,
)
from sim.physics.sweep import static_geometry
from sim.physics.world import new_space, robot_bodies
from sim.scenario import Scenario

NOISE_BLOCK = 4096  # normals drawn per refill of a robot's wheel-noise buffer
_DELTAS = np.array(ACTION_DELTAS, dtype=np.int64)
_HEADINGS = np.array(ACTION_HEADINGS, dtype=np.float64)


@dataclass(frozen=True)
class PrimitiveOutcome:
    """What one batched step did, one entry per robot (inactive robots: zeros)."""

    state: np.ndarray  # int64[N]: the cell of the final pose (Discretiser.state_of)
    bumped: np.ndarray  # bool[N]: a contact began; the robot is back on its start centre
    reached: np.ndarray  # bool[N]: ended within tolerance of the target centre and heading
    timeout: np.ndarray  # bool[N]: gave up at PhysicsConfig.timeout_s
    steps: np.ndarray  # int64[N]: physics steps driven
    contacts: np.ndarray  # int64[N]: contacts that began


class RouteBatch:
    """N robots in one Space, each driving grid actions as motion primitives.

    ``guards`` may be shared between batches of one scenario and config (it is a pure
    function of the static geometry). ``trajectories=True`` keeps the pose after every
    physics step of the last primitive (:meth:`trajectory`), as the env's ``info`` wants.
    """

    def __init__(self, scenario: Scenario, n_robots: int, config: PhysicsConfig | None = None,
                 *, trajectories: bool = False, guards: np.ndarray | None = None,
                 fidelity: Fidelity | None = None) -> None:
        if not (isinstance(n_robots, int) and n_robots >= 1):
            raise ValueError(f"n_robots must be an int >= 1, got {n_robots!r}")
        self.scenario = sc = scenario
        self.config = cfg = config or PhysicsConfig()
        cfg.validate()
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
        # controller constants (the same tables as PrimitiveController)
        lim = DriveLimits.from_robot(sc.robot)
        period = cfg.control_period_s
        self._period = period
        drive = ProfileTable(lim.v_max_m_s, lim.a_max_m_s2 * period)
        turn = ProfileTable(lim.omega_max_rad_s, lim.alpha_max_rad_s2 * period)
        self._drive_caps, self._drive_sums = K.profile_arrays(drive, 8.0 * self.cell_m / period)
        self._turn_caps, self._turn_sums = K.profile_arrays(turn, 1.01 * math.pi / period)
        self._timeout_steps = math.ceil(cfg.timeout_s / cfg.dt_s - 1e-9)
        n_s = self.nx * self.ny
        if guards is None:
            guards = np.full((n_s, 4), np.nan)
        elif guards.shape != (n_s, 4):
            raise ValueError(f"guards must have shape {(n_s, 4)}, got {guards.shape}")
        self.guards = guards
        self.fs = np.zeros((n_robots, K.NF))
        self.ist = np.zeros((n_robots, K.NI), dtype=np.int64)
        self.fs[:, K.X], self.fs[:, K.Y] = x0, y0
        cap = (self._timeout_steps + 2 * (self._drive_sums.size + self._turn_sums.size) + 8
               if trajectories else 0)
        self._traj = np.zeros((n_robots, cap, 3))
        self._ntraj = np.zeros(n_robots, dtype=np.int64)
        self._traj_start = np.zeros((n_robots, 3))
        self._all = np.ones(n_robots, dtype=np.bool_)
        self._states = np.zeros(n_robots, dtype=np.int64)
        self.contacts: list[list[Contact]] = [[] for _ in range(n_robots)]
        self.contact_counts = [dict.fromkeys(CollisionType, 0) for _ in range(n_robots)]
        self._casts = np.zeros(1, dtype=np.int64)  # guard casts so far (compiled)
        self.checks = 0  # Chipmunk contact checks so far (benchmark figures)
        self.kernel_s = 0.0  # wall time in the compiled kernel so far [s]
        self.chipmunk_s = 0.0  # wall time in Chipmunk contact checks so far [s]
        self.fidelity = fid = fidelity or Fidelity()
        fid.validate()
        # each robot's normals for wheel noise, drawn in blocks from its own generator
        self._noise = np.zeros((n_robots, NOISE_BLOCK if fid.wheel_noise > 0 else 2))
        self._npos = np.full(n_robots, self._noise.shape[1], dtype=np.int64)
        self._noise_rngs: list[np.random.Generator | None] = [None] * n_robots
        self._half_base_m = 0.5 * sc.robot.wheel_base_m
        self.geometry = g = static_geometry(sc)
        self._seen = np.zeros(len(g.circles) + len(g.boxes), dtype=np.int64)
        self._stamp = np.zeros(1, dtype=np.int64)
        sigint.install(RouteBatch._check)

    def _add_robot(self, x: float, y: float) -> None:
        body, shape, control, pivot, gear = robot_bodies(self.scenario, self.config, x, y, 0.0)
        self.space.add(body, shape, control, pivot, gear)
        self.bodies.append(body)
        self.shapes.append(shape)

    # ------------------------------------------------------------------ episodes
    def place(self, i: int, x_m: float, y_m: float, heading_rad: float = 0.0, *,
              resting: bool = False) -> None:
        """Put robot ``i`` at rest at a pose: a new episode (its step clock and contacts reset).
        ``resting``: it rests against a surface there, as a bump at carried pose leaves it
        (a stochastic model restarts robots from such poses)."""
        fs, ist = self.fs, self.ist
        fs[i, :] = 0.0
        fs[i, K.X], fs[i, K.Y], fs[i, K.TH] = x_m, y_m, heading_rad
        ist[i, :] = 0
        if resting:
            ist[i, K.INCONTACT] = 1
        self.contacts[i] = []
        self.contact_counts[i] = dict.fromkeys(CollisionType, 0)
        self._ntraj[i] = 0
        body = self.bodies[i]
        body.position, body.angle = (x_m, y_m), heading_rad
        body.velocity, body.angular_velocity = (0.0, 0.0), 0.0

    def pose(self, i: int) -> tuple[float, float, float]:
        """(x [m], y [m], heading [rad], not wrapped) of robot ``i``."""
        return float(self.fs[i, K.X]), float(self.fs[i, K.Y]), float(self.fs[i, K.TH])

    def steps(self, i: int) -> int:
        """Physics steps robot ``i`` has driven since it was placed."""
        return int(self.ist[i, K.STEPS])

    def time_s(self, i: int) -> float:
        return self.steps(i) * self.config.dt_s

    def trajectory(self, i: int) -> np.ndarray:
        """float64[n, 3]: robot ``i``'s pose before its last primitive, then after each step."""
        n = int(self._ntraj[i])
        return np.concatenate([self._traj_start[i][None], self._traj[i, :n]])

    def sync_body(self, i: int) -> pymunk.Body:
        """Robot ``i``'s body in the Space, moved to the robot's pose (for queries, drawing)."""
        body = self.bodies[i]
        body.position = (float(self.fs[i, K.X]), float(self.fs[i, K.Y]))
        body.angle = float(self.fs[i, K.TH])
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
        fs, ist = self.fs, self.ist
        if self._traj.shape[1]:
            self._traj_start[:] = fs[:, K.X:K.TH + 1]
            self._ntraj[act] = 0
        K.begin_all(fs, ist, acts, act, self.cell_m, self.nx, self.ny, _DELTAS, _HEADINGS)
        cfg = self.config
        clock = time.perf_counter
        g, fid = self.geometry, self.fidelity
        while True:
            t0 = clock()
            K.advance(fs, ist, act, cfg.dt_s, cfg.substeps, self._period, cfg.tolerance_m,
                      cfg.tolerance_rad, self._timeout_steps, cfg.contact_depth_m, self.cell_m,
                      self.nx, self.ny, self.guards, self._turn_caps, self._turn_sums,
                      self._drive_caps, self._drive_sums, self._traj, self._ntraj,
                      self.radius_m, g.circles, g.walls, g.boxes, g.start, g.items, self._seen,
                      self._stamp, self._casts, fid.wheel_noise, fid.carried_pose,
                      self._half_base_m, self._noise, self._npos, fid.bumper_travel_m)
            t1 = clock()
            self.kernel_s += t1 - t0
            status = ist[:, K.STATUS]
            waiting = np.flatnonzero(act & (status != K.DONE))
            if waiting.size == 0:
                break
            for i in waiting:
                if status[i] == K.NOISE:
                    self._refill(int(i))
                else:
                    self._check(int(i))
            self.chipmunk_s += clock() - t1
            sigint.raise_if_deferred()
        K.states_of(fs, self.cell_m, self.nx, self.ny, self._states)
        return PrimitiveOutcome(
            state=np.where(act, self._states, 0), bumped=act & (ist[:, K.BUMPED] == 1),
            reached=act & (ist[:, K.REACHED] == 1), timeout=act & (ist[:, K.TIMEOUT] == 1),
            steps=np.where(act, ist[:, K.STEPS] - ist[:, K.STEPS0], 0),
            contacts=np.where(act, ist[:, K.NCONTACT], 0))

    @property
    def casts(self) -> int:
        """Guard casts so far (legs whose guard was not cached)."""
        return int(self._casts[0])

    def set_noise_rng(self, i: int, rng: np.random.Generator) -> None:
        """Robot ``i``'s wheel noise comes from ``rng`` from now on (its buffer is emptied)."""
        self._noise_rngs[i] = rng
        self._npos[i] = self._noise.shape[1]

    def _refill(self, i: int) -> None:
        rng = self._noise_rngs[i]
        if rng is None:
            raise RuntimeError(f"robot {i} has wheel noise but no generator: call "
                               "set_noise_rng(i, rng) first")
        self._noise[i] = rng.standard_normal(self._noise.shape[1])
        self._npos[i] = 0

    def _check(self, i: int) -> None:
        """Did a contact begin in robot ``i``'s last step? Chipmunk's narrow phase decides."""
        self.checks += 1
        fs, ist = self.fs, self.ist
        shape = self.shapes[i]
        forced = ist[i, K.FORCED] == 1
        if forced:  # it pushed into what it rests against: undo the step, record the contact
            fs[i, K.X], fs[i, K.Y], fs[i, K.TH] = fs[i, K.PX], fs[i, K.PY], fs[i, K.PTH]
        self.sync_body(i)
        found = self.space.shape_query(shape)
        if not forced and ist[i, K.INCONTACT] == 1 and found:
            # resting contacts are not new ones: only shapes it did not touch before the step
            body = self.bodies[i]
            body.position, body.angle = (float(fs[i, K.PX]), float(fs[i, K.PY])), 0.0
            self.space.reindex_shapes_for_body(body)
            before = {info.shape for info in self.space.shape_query(shape)}
            self.sync_body(i)
            found = [info for info in found if info.shape not in before]
        if not found and not forced:
            return  # the kernel finishes the step
        step = int(ist[i, K.STEPS])
        for info in found:
            kind = CollisionType(info.shape.collision_type)
            cps = info.contact_point_set
            deepest = min(cps.points, key=lambda p: p.distance)
            self.contacts[i].append(Contact(step, kind, deepest.point_a.x, deepest.point_a.y,
                                            cps.normal.x, cps.normal.y, -deepest.distance))
            self.contact_counts[i][kind] += 1
        ist[i, K.NCONTACT] += max(len(found), 1)
        if self.fidelity.carried_pose:
            K.bump_stay(fs, ist, i, False)
        else:
            K.bump_back(fs, ist, i)


class RobotView:
    """One robot of a :class:`RouteBatch`, read like a :class:`sim.physics.world.PhysicsWorld`
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

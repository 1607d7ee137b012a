"""The physics world at a fidelity as a stochastic model: states, contexts, the model's arrays.

At ``exact`` a primitive has one outcome per cell and the physics world's tabular model
(:mod:`sim.physics.models.transition`) is the whole truth. Above it a primitive has a
distribution of outcomes, and what it depends on is more than the cell:

- with carried pose a bump leaves the robot resting against a surface wherever the
  contact stopped it, and the next primitive starts from there;
- with wheel noise the turn in place before a drive makes position error, so the heading
  the robot arrived with matters (paper-40's shortest route, one cell beside an obstacle:
  bump probability 0.145 when the robot already faces the way it goes, 0.25 from a drawn
  cardinal heading).

So a state is ``(cell, context, particle)``. Contexts:

- :data:`ARRIVED` (0): near the centre, heading irrelevant (no wheel noise: the closed-loop
  controller ends every primitive within 2 cm / 2 degrees of its target, and a noise-free
  turn in place does not move the disc). Drives start on the centre, a drawn cardinal
  heading. At ``exact`` a bump places the robot back on its start centre, so this is the
  only context there and the model is :func:`sim.physics.models.transition.physics_model`.
- ``FACING + a`` (5..8), *arrived doing action a* (with wheel noise): near the centre,
  facing a's heading. Drives start from a pose drawn from the pool of poses that drives
  into this state really ended in (within the controller's tolerance). An episode starts
  at S facing +x, i.e. ``FACING + right``.
- ``RESTING + a`` (1..4), *stopped away from the target doing action a* (a bump at carried
  pose, or a timeout), at one of up to ``Sampling.particles`` representative rest poses
  (*particles*, drawn from the rest poses the build produced in that cell and context);
  a drive ending there is assigned to the nearest particle (:func:`nearest`), and
  drives from a particle start on its exact pose, resting in contact if it was.

Why particles and not one pool per (cell, context): a robot that fails to move off a
surface is still where it was, so its retries are not independent draws. Beside an
obstacle a few millimetres along the surface decide whether a retry of the same action
ever frees it (paper-40, the cell the exact BFS route grazes: every rest pose below a
line 1 cm before the cell's edge is a trap, every one above it comes free). Drawing each
retry's start from one pool made the pinned robot escape with probability 1 in the model
(the BFS policy at ``noisy``: P(G) 1.00 in the pooled model, 0.93 driven); with
particles, a particle from which every drive bumps is a trap, as in the world (0.93).

Index ``n_states`` is G (absorbing, every context). Everything about building it is in
:mod:`sim.physics.models.build`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS, N_ACTIONS
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.batch import PrimitiveOutcome

ARRIVED = 0  # near the centre, heading irrelevant (no wheel noise)
RESTING = 1  # RESTING + a: stopped away from the target doing action a (a bump, a timeout)
FACING = RESTING + N_ACTIONS  # FACING + a: near the centre, facing action a's heading
N_CONTEXTS = FACING + N_ACTIONS
RIGHT = ACTION_HEADINGS.index(0.0)  # the action whose heading an episode starts with
TURN_M_PER_RAD = 0.1  # pose distance: a radian of turn to the target counts as 10 cm [m/rad]
DEFAULT_SAMPLES = 32  # K: drives per (state, action) above exact
REFINE = 8  # pairs whose K drives disagree are driven up to REFINE * K times in all
DEFAULT_PARTICLES = 32  # representative rest poses per resting (cell, context)
DEFAULT_PARTICLE_SAMPLES = 4  # drives per (particle, action): one exact pose, noise only
MAX_SAMPLES = 100_000


def start_context(fid: Fidelity) -> int:
    """The context of S when an episode starts (on its centre, facing +x)."""
    return FACING + RIGHT if fid.wheel_noise > 0 else ARRIVED


def next_context(out: PrimitiveOutcome, actions: np.ndarray, fid: Fidelity) -> np.ndarray:
    """int64[N]: the context a primitive left each robot in (see the module doc; a bump
    without carried pose places the robot back facing the way it drove)."""
    rest = (out.bumped & fid.carried_pose) | (out.timeout & ~out.bumped)
    arrived = FACING + actions if fid.wheel_noise > 0 else np.full_like(actions, ARRIVED)
    return np.where(rest, RESTING + actions, arrived)


def is_resting(context: np.ndarray | int) -> np.ndarray | bool:
    return (context >= RESTING) & (context < FACING)


def rest_features(poses: np.ndarray, family: int, nx: int, cell_m: float) -> np.ndarray:
    """float64[q, 3]: what tells rest poses (q x >=3: x, y, heading) of one resting family
    (``cell * N_CONTEXTS + RESTING + a``) apart: x, y [m] and the turn [rad] a retry of
    action a would begin with, times :data:`TURN_M_PER_RAD`. Where the robot rests
    decides (a trap or not is a matter of millimetres along the surface); the turn only
    tells apart a robot that already faces its target (it failed a retry) from one that
    turns first, and the noise of that turn moves it a little: it counts little."""
    cell, a = divmod(family, N_CONTEXTS)
    dx, dy = ACTION_DELTAS[a - RESTING]
    tx = (cell % nx + dx + 0.5) * cell_m
    ty = (cell // nx + dy + 0.5) * cell_m
    turn = poses[:, 2] - np.arctan2(ty - poses[:, 1], tx - poses[:, 0])
    turn = (turn + math.pi) % (2 * math.pi) - math.pi
    return np.column_stack([poses[:, 0], poses[:, 1], TURN_M_PER_RAD * turn])


def feature_distances(features: np.ndarray, particles: np.ndarray) -> np.ndarray:
    """float64[q, m]: distance [m] between :func:`rest_features` rows: in the plane plus
    the scaled turn."""
    p, q = particles[None], features[:, None]
    return np.hypot(q[..., 0] - p[..., 0], q[..., 1] - p[..., 1]) + np.abs(q[..., 2] - p[..., 2])


def nearest(particles: np.ndarray, features: np.ndarray) -> np.ndarray:
    """int64[q]: for each of ``features`` the nearest of ``particles`` (both
    :func:`rest_features` of one family)."""
    return feature_distances(features, particles).argmin(axis=1)


@dataclass(frozen=True)
class Sampling:
    """How many drives make the model.

    Every arrived state's actions are driven ``samples`` (K) times; a (state, action) whose
    K drives did not all reach the same next (cell, context) is driven again until it has
    ``refined`` drives: the figures' precision is decided at the few pairs beside an
    obstacle where a few centimetres of drift decide a bump (with K = 32 a bump
    probability of 0.1 has a standard error of 0.05; with 256, 0.02), and most pairs have
    one outcome. A resting (cell, context) has up to ``particles`` rest poses, each
    action driven ``particle_samples`` times from that exact pose (only the noise varies:
    enough to tell a trap, from which every drive bumps, from a pose the robot leaves)."""

    samples: int = DEFAULT_SAMPLES  # K [drives per (arrived state, action)]
    refined: int = REFINE * DEFAULT_SAMPLES  # [drives per such pair that disagreed]
    particles: int = DEFAULT_PARTICLES  # [rest poses per resting (cell, context)]
    particle_samples: int = DEFAULT_PARTICLE_SAMPLES  # [drives per (particle, action)]
    seed: int = 0  # of the start-pose draws and every batch slot's noise stream

    @classmethod
    def default(cls, fid: Fidelity, samples: int | None = None, seed: int = 0) -> Sampling:
        """K = 1 at ``exact`` (one outcome per (cell, action)), else :data:`DEFAULT_SAMPLES`,
        refined to :data:`REFINE` times K where a primitive has several outcomes; particle
        drives as K up to :data:`DEFAULT_PARTICLE_SAMPLES`."""
        k = (1 if fid.is_exact else DEFAULT_SAMPLES) if samples is None else samples
        return cls(k, k if fid.is_exact else REFINE * k, DEFAULT_PARTICLES,
                   min(k, DEFAULT_PARTICLE_SAMPLES), seed)

    def validate(self) -> None:
        for name in ("samples", "refined", "particles", "particle_samples"):
            v = getattr(self, name)
            if not (isinstance(v, int) and 1 <= v <= MAX_SAMPLES):
                raise ValueError(f"{name} must be an int in 1..{MAX_SAMPLES}, got {v!r}")
        if self.refined < self.samples:
            raise ValueError(f"refined ({self.refined}) must be >= samples ({self.samples})")
        if not (isinstance(self.seed, int) and self.seed >= 0):
            raise ValueError(f"seed must be an int >= 0, got {self.seed!r}")


@dataclass(frozen=True, eq=False)
class StochasticModel:
    """The driven model. State ``i`` is cell ``state_cell[i]``, context
    ``state_context[i]`` and, when resting, the particle ``state_pose[i]``; index
    ``n_states`` is G. Transitions of ``(i, a)`` are the rows
    ``sa_ptr[4i + a] : sa_ptr[4i + a + 1]`` of ``dst`` (next state) and ``prob``."""

    fidelity: Fidelity
    sampling: Sampling
    nx: int
    ny: int
    cell_m: float  # cell size [m]
    start_cell: int
    goal_cell: int
    state_cell: np.ndarray  # int32[n]
    state_context: np.ndarray  # int8[n]
    state_pose: np.ndarray  # float64[n, 4]: a particle's x, y [m], heading [rad], in contact
    #                         (0/1); nan for states that are not particles
    sa_ptr: np.ndarray  # int64[4n + 1]
    dst: np.ndarray  # int32[m]; n = G
    prob: np.ndarray  # float64[m]; empirical next-state probabilities [-]
    mean_steps: np.ndarray  # float64[n, 4]: physics steps per primitive (times dt_s: seconds)
    primitives: int  # primitives driven to build the model
    build_s: float  # wall time of the build [s] (of the original build when loaded)
    timeouts: int  # primitives that gave up at the timeout (resting where they stopped)

    @property
    def n_states(self) -> int:
        return int(self.state_cell.size)

    @property
    def goal(self) -> int:
        """The index of G."""
        return self.n_states

    @property
    def start(self) -> int:
        """The index of S at an episode's start (G's index when S is G)."""
        hit = np.flatnonzero((self.state_cell == self.start_cell)
                             & (self.state_context == start_context(self.fidelity)))
        return int(hit[0]) if hit.size else self.goal

    @property
    def src_sa(self) -> np.ndarray:
        """int64[m]: the ``4 * state + action`` each transition row belongs to."""
        return np.repeat(np.arange(self.sa_ptr.size - 1), np.diff(self.sa_ptr))

    def p_goal(self) -> np.ndarray:
        """float64[n, 4]: probability that the primitive ends in G."""
        hit = np.where(self.dst == self.goal, self.prob, 0.0)
        return np.bincount(self.src_sa, hit, minlength=4 * self.n_states).reshape(-1, 4)

    def context_counts(self) -> np.ndarray:
        """int64[N_CONTEXTS]: states per context (see the module doc)."""
        return np.bincount(self.state_context, minlength=N_CONTEXTS)


class Locator:
    """Which state of a model a robot is in, from its cell, context and pose (a driven
    rollout of a policy per state; the build assigns its drives the same way)."""

    def __init__(self, model: StochasticModel) -> None:
        self.states: dict[tuple[int, int], np.ndarray] = {}
        order = np.lexsort((model.state_context, model.state_cell))
        cells, ctxs = model.state_cell[order], model.state_context[order]
        bounds = np.flatnonzero(np.diff(cells * N_CONTEXTS + ctxs)) + 1
        for group in np.split(order, bounds) if order.size else []:
            self.states[(int(model.state_cell[group[0]]),
                         int(model.state_context[group[0]]))] = group
        self.features = {fam: rest_features(model.state_pose[group], fam[0] * N_CONTEXTS
                                            + fam[1], model.nx, model.cell_m)
                         for fam, group in self.states.items() if group.size > 1}
        self.nx, self.cell_m = model.nx, model.cell_m
        self.goal_cell, self.goal = model.goal_cell, model.goal

    def state(self, cell: int, context: int, pose: np.ndarray) -> int:
        """The state index (G's for the goal cell; -1 when the model has no such state)."""
        if cell == self.goal_cell:
            return self.goal
        group = self.states.get((cell, context))
        if group is None:
            return -1
        if group.size == 1:
            return int(group[0])
        family = cell * N_CONTEXTS + context
        here = rest_features(np.asarray(pose, dtype=np.float64)[None], family, self.nx,
                             self.cell_m)
        return int(group[nearest(self.features[(cell, context)], here)[0]])

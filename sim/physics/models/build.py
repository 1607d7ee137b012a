"""Building the stochastic model (:mod:`sim.physics.models.stochastic`) by driving, and caching it.

From S's start state outward (breadth first, until no new state turns up), every
arrived state's four actions are driven K times and every particle's ``particle_samples``
times (:class:`sim.physics.models.stochastic.Sampling`), as the robots of one
:class:`sim.physics.kernel.batch.RouteBatch` (256 at a time, each batch slot with its own noise
stream spawned from the seed, so a build is a pure function of its inputs); an arrived
(state, action) whose K drives did not all end in the same (cell, context) is driven
again up to the refined count. A drive's next state is the cell it ends in and its
context (:func:`sim.physics.models.stochastic.next_context`), and for a resting context
the particle nearest to where it stopped. Every primitive costs the same (1); the mean
physics steps per (state, action) are kept too (seconds: times ``dt_s``).

Cost (measured, 2 shared cores, see the README): paper-50 at ``noisy`` drives about 2.1M
primitives (some 100 s); paper-40 1.4M; at ``exact`` 4 per reachable cell (a second).

Order: states whose start poses are known (arrived ones) are expanded before resting
ones, so that when a resting (cell, context) gets its particles (drawn from the rest
poses produced so far), the drives of every arrived state that bumps into it are among
them. Rest poses that arrive later are assigned to the nearest particle like any other.

Built models are cached in-process and on disk
(``$XDG_CACHE_HOME/rnhql/stochastic-model/<digest>.npz``; the digest holds the scenario,
physics config, fidelity, sampling, batch size and a hash of the source of the modules a
drive runs through, so a new contact rule means a new model). :mod:`sim.physics.models.disk_cache`
checks a file before it is used (format, key, the SHA-256 of its content), rebuilds one that
fails and says so; this model's own check is :func:`_check` (dtypes, shapes, the
scenario's size, indices in range, probabilities). ``RNHQL_NO_DISK_CACHE=1`` turns the disk
cache off.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import time
from functools import lru_cache
from pathlib import Path

import numpy as np
import pymunk

from sim.errors import ScenarioError
from sim.grid.actions import N_ACTIONS
from sim.grid.discretiser import Discretiser
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.models import disk_cache
from sim.physics.models.stochastic import (
    ARRIVED,
    N_CONTEXTS,
    Sampling,
    StochasticModel,
    feature_distances,
    is_resting,
    nearest,
    next_context,
    rest_features,
    start_context,
)
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

FORMAT = "rnhql-stochastic-model-4"  # 4: with its key and the SHA-256 of its content
BATCH = 256  # robots per batched step while building
_NAN_POSE = np.full(4, np.nan)


class _Builder:
    """Breadth-first expansion of states by driving. A *family* is ``cell * N_CONTEXTS +
    context``; a resting family has up to ``particles`` states, any other exactly one."""

    def __init__(self, sc: Scenario, fid: Fidelity, sampling: Sampling,
                 config: PhysicsConfig) -> None:
        self.sc, self.fid, self.sampling = sc, fid, sampling
        self.disc = disc = Discretiser.from_scenario(sc)
        self.goal = disc.index(*sc.goal)
        self.cells: list[int] = []  # per state
        self.contexts: list[int] = []
        self.poses: list[np.ndarray] = []  # a particle's pose (nan for other states)
        self.state_of: dict[int, int] = {}  # non-resting family -> its state
        self.particles_of: dict[int, np.ndarray] = {}  # resting family -> its states
        self.known: set[int] = set()
        self.closed: set[int] = set()  # families whose start poses are fixed: no more pooling
        self.pending_states: list[int] = []
        self.pending_families: list[int] = []
        self.pools: dict[int, list[np.ndarray]] = {}  # family -> end poses [x, y, th, contact]
        seq = np.random.SeedSequence(sampling.seed)
        pose_seq, noise_seq = seq.spawn(2)
        self.rng = np.random.default_rng(pose_seq)
        self.batch = RouteBatch(sc, BATCH, config, fidelity=fid, contact_records=False)
        for i, child in enumerate(noise_seq.spawn(BATCH)):
            self.batch.set_noise_rng(i, np.random.default_rng(child))
        self.rows: list[tuple[np.ndarray, ...]] = []  # src_sa, family (-1: G), steps, end
        self.primitives = 0
        self.timeouts = 0

    def new_state(self, family: int, pose: np.ndarray = _NAN_POSE) -> int:
        self.cells.append(family // N_CONTEXTS)
        self.contexts.append(family % N_CONTEXTS)
        self.poses.append(pose)
        return len(self.cells) - 1

    def discover(self, families: np.ndarray) -> None:
        for f in np.unique(families).tolist():
            if f < 0 or f in self.known:
                continue
            self.known.add(f)
            if is_resting(f % N_CONTEXTS):
                self.pending_families.append(f)
            else:
                self.state_of[f] = s = self.new_state(f)
                self.pending_states.append(s)

    def run(self) -> None:
        start = self.disc.index(*self.sc.start)
        if start == self.goal:
            return
        family = start * N_CONTEXTS + start_context(self.fid)
        self.pools[family] = [np.array([[*self.disc.state_centre(start), 0.0, 0.0]])]  # reset
        self.discover(np.array([family]))
        while self.pending_states or self.pending_families:
            if self.pending_states:  # arrived states first: their bumps fill the rest pools
                layer, self.pending_states = self.pending_states, []
            else:
                families, self.pending_families = self.pending_families, []
                layer = [s for f in families for s in self.make_particles(f)]
            self.drive(np.array(layer, dtype=np.int64))

    def make_particles(self, family: int) -> list[int]:
        """Up to ``particles`` states at rest poses of the family's pool, spread over it by
        k-means++ seeding (each next pose drawn with probability proportional to its
        squared distance to the nearest chosen one: dense stretches of a surface get
        more particles, a rare one its own)."""
        pool = np.concatenate(self.pools.pop(family))
        self.closed.add(family)
        feats = rest_features(pool, family, self.sc.nx, self.sc.cell_size_m)
        pick = [int(self.rng.integers(len(pool)))]
        gap = np.full(len(pool), np.inf)
        for _ in range(min(self.sampling.particles, len(pool)) - 1):
            gap = np.minimum(gap, feature_distances(feats, feats[pick[-1]][None])[:, 0])
            weight = gap * gap
            if weight.sum() <= 0.0:
                break
            pick.append(int(self.rng.choice(len(pool), p=weight / weight.sum())))
        states = [self.new_state(family, pool[i]) for i in sorted(pick)]
        self.particles_of[family] = np.array(states, dtype=np.int64)
        return states

    def starts(self, states: np.ndarray) -> np.ndarray:
        """float64[len(states), 4]: a start pose (x, y, heading) per drive from these states
        and whether the robot rests in contact there (1) or not (0)."""
        c = self.sc.cell_size_m
        cells = np.asarray(self.cells)[states]
        ctx = np.asarray(self.contexts)[states]
        poses = np.asarray(self.poses)[states]  # particles: their own pose
        arrived = ctx == ARRIVED
        poses[arrived, 0] = (cells[arrived] % self.sc.nx + 0.5) * c
        poses[arrived, 1] = (cells[arrived] // self.sc.nx + 0.5) * c
        poses[arrived, 2] = self.rng.integers(0, 4, int(arrived.sum())) * (math.pi / 2)
        poses[arrived, 3] = 0.0
        families = cells * N_CONTEXTS + ctx
        pooled = ~arrived & ~is_resting(ctx)
        for f in np.unique(families[pooled]).tolist():
            rows = np.flatnonzero(pooled & (families == f))
            pool = np.concatenate(self.pools[f])
            self.pools[f] = [pool]
            poses[rows] = pool[self.rng.integers(0, len(pool), rows.size)]
        return poses

    def drive(self, states: np.ndarray) -> None:
        """Drive every action of these states K times, then again up to the refined count
        where the K drives did not all end in one (cell, context)."""
        sp = self.sampling
        resting = is_resting(np.asarray(self.contexts)[states])
        k = np.where(resting, sp.particle_samples, sp.samples)
        job_states = np.repeat(states, N_ACTIONS * k)
        actions = np.concatenate([np.repeat(np.arange(N_ACTIONS), j) for j in k.tolist()])
        src_sa, fam = self.drive_jobs(job_states, actions)
        self.discover(fam)
        arrived = ~np.isin(src_sa // N_ACTIONS, states[resting])
        src_sa, fam = src_sa[arrived], fam[arrived]
        if sp.refined > sp.samples and src_sa.size:
            k, refined = sp.samples, sp.refined
            pairs = np.unique(np.stack([src_sa, fam]), axis=1)[0]
            multi = np.flatnonzero(np.bincount(pairs) > 1)
            if multi.size:
                more = np.repeat(multi, refined - k)
                _, fam = self.drive_jobs(more // N_ACTIONS, more % N_ACTIONS)
                self.discover(fam)
        for s in states.tolist():
            family = self.cells[s] * N_CONTEXTS + self.contexts[s]
            self.closed.add(family)
            self.pools.pop(family, None)

    def drive_jobs(self, job_states: np.ndarray, actions: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Drive ``actions[j]`` from state ``job_states[j]``, BATCH at a time; record it."""
        fid, batch = self.fid, self.batch
        poses = self.starts(job_states)
        n_jobs = poses.shape[0]
        fam = np.empty(n_jobs, dtype=np.int64)
        steps = np.empty(n_jobs, dtype=np.int64)
        end = np.empty((n_jobs, 3))
        act = np.zeros(BATCH, dtype=np.bool_)
        acts = np.zeros(BATCH, dtype=np.int64)
        for lo in range(0, n_jobs, BATCH):
            n = min(BATCH, n_jobs - lo)
            p = poses[lo:lo + n]
            batch.place_many(np.arange(n), p[:, 0], p[:, 1], p[:, 2], p[:, 3] > 0)
            act[:] = False
            act[:n] = True
            acts[:n] = actions[lo:lo + n]
            out = batch.step(acts, act)
            cell = out.state[:n]
            f = cell * N_CONTEXTS + next_context(out, acts, fid)[:n]
            fam[lo:lo + n] = np.where(cell == self.goal, -1, f)
            steps[lo:lo + n] = out.steps[:n]
            end[lo:lo + n] = batch.poses()[:n]
            self.timeouts += int(out.timeout[:n].sum())
            self.pool(fam[lo:lo + n])
        self.primitives += n_jobs
        src_sa = job_states * N_ACTIONS + actions
        self.rows.append((src_sa, fam, steps, end))
        return src_sa, fam

    def pool(self, fam: np.ndarray) -> None:
        """Add the end poses of the batch's first ``len(fam)`` robots to their families'
        pools (for families whose start poses are still to be drawn from them)."""
        keep = (fam >= 0) & (fam % N_CONTEXTS != ARRIVED)
        keep &= np.array([f not in self.closed for f in fam.tolist()], dtype=bool)
        rows = np.flatnonzero(keep)
        if rows.size == 0:
            return
        poses = np.column_stack([self.batch.poses()[rows], self.batch.r.resting[rows]])
        order = np.argsort(fam[rows], kind="stable")
        uniq, first = np.unique(fam[rows][order], return_index=True)
        for f, chunk in zip(uniq.tolist(), np.split(poses[order], first[1:]), strict=True):
            self.pools.setdefault(f, []).append(chunk)

    def model(self, build_s: float) -> StochasticModel:
        n = len(self.cells)
        if self.rows:
            src_sa, fam, steps, end = (np.concatenate(c) for c in zip(*self.rows, strict=True))
        else:
            src_sa = fam = steps = np.zeros(0, dtype=np.int64)
            end = np.zeros((0, 3))
        dst = np.full(fam.size, n, dtype=np.int64)  # G
        order = np.argsort(fam, kind="stable")
        uniq, first = np.unique(fam[order], return_index=True)
        poses = np.asarray(self.poses).reshape(n, 4)
        for f, rows in zip(uniq.tolist(), np.split(order, first[1:]), strict=True):
            if f < 0:
                continue
            if f in self.state_of:
                dst[rows] = self.state_of[f]
            else:
                states = self.particles_of[f]
                nx, c = self.sc.nx, self.sc.cell_size_m
                dst[rows] = states[nearest(rest_features(poses[states], f, nx, c),
                                           rest_features(end[rows], f, nx, c))]
        return from_samples(self.fid, self.sampling, self.sc, np.asarray(self.cells),
                            np.asarray(self.contexts), poses, src_sa, dst, steps,
                            self.primitives, build_s, self.timeouts)


def from_samples(fid: Fidelity, sampling: Sampling, sc: Scenario, cells: np.ndarray,
                 contexts: np.ndarray, poses: np.ndarray, src_sa: np.ndarray,
                 dst: np.ndarray, steps: np.ndarray, primitives: int, build_s: float,
                 timeouts: int) -> StochasticModel:
    """The model of driven samples: per drive ``src_sa`` (4 * state + action) and ``dst``
    (next state; ``len(cells)`` for G), for states ``(cells, contexts, poses)``."""
    n = cells.size
    code = src_sa * (n + 1) + dst
    uniq, counts = np.unique(code, return_counts=True)
    rows_sa, rows_dst = uniq // (n + 1), uniq % (n + 1)
    per_sa = np.bincount(src_sa, minlength=N_ACTIONS * n)
    sa_ptr = np.zeros(N_ACTIONS * n + 1, dtype=np.int64)
    sa_ptr[1:] = np.cumsum(np.bincount(rows_sa, minlength=N_ACTIONS * n))
    mean_steps = np.bincount(src_sa, steps.astype(np.float64), minlength=N_ACTIONS * n)
    mean_steps = mean_steps / np.maximum(per_sa, 1)
    disc = Discretiser.from_scenario(sc)
    return StochasticModel(
        fidelity=fid, sampling=sampling, nx=sc.nx, ny=sc.ny, cell_m=sc.cell_size_m,
        start_cell=disc.index(*sc.start),
        goal_cell=disc.index(*sc.goal), state_cell=cells.astype(np.int32),
        state_context=contexts.astype(np.int8), state_pose=poses.astype(np.float64),
        sa_ptr=sa_ptr, dst=rows_dst.astype(np.int32), prob=counts / per_sa[rows_sa],
        mean_steps=mean_steps.reshape(n, N_ACTIONS), primitives=int(primitives),
        build_s=float(build_s), timeouts=int(timeouts))


def build_stochastic_model(sc: Scenario, fidelity: Fidelity | None = None,
                           sampling: Sampling | None = None,
                           config: PhysicsConfig | None = None) -> StochasticModel:
    """Drive the model of ``sc`` at ``fidelity`` (no cache; see :func:`stochastic_model`)."""
    fid = fidelity or Fidelity()
    refuse_hidden_state(fid)
    sampling = sampling or Sampling.default(fid)
    sampling.validate()
    t0 = time.perf_counter()
    builder = _Builder(sc, fid, sampling, config or PhysicsConfig())
    builder.run()
    return builder.model(time.perf_counter() - t0)


def refuse_hidden_state(fid: Fidelity) -> None:
    """The model's states are cells and contexts: at a rung with hidden state (open loop:
    the offset within the cell carries over; localisation: the estimate's error does) the
    world is not Markov in them, and a V* built on them would be a wrong yardstick."""
    if fid.hidden_state:
        raise ScenarioError("--fidelity", "fidelity", f"{fid.label} has hidden state (open "
                            "loop or localisation): the stochastic model's states (cell, "
                            "context) do not capture it, so V* is not defined there",
                            "grade by driving (rnhql compare ... --fidelity F) and compare "
                            "with the best method; V* exists at exact, noisy, slippery and "
                            "uncalibrated")


# ---------------------------------------------------------------------------- caching
def cache_dir() -> Path:
    return disk_cache.cache_dir(CACHE)


@lru_cache(maxsize=1)
def _code_digest() -> str:
    """A hash of the source of every module a drive runs through: a change to the world
    (the kernel's contact rule, the controller) must not be answered from an old model."""
    from sim.physics import static
    from sim.physics.kernel import batch, sweep
    from sim.physics.kernel import primitive as K
    from sim.physics.kernel import state as kernel_state
    from sim.physics.models import stochastic as model
    from sim.physics.reference import controller, world

    h = hashlib.sha256()
    for mod in (K, kernel_state, batch, controller, static, sweep, world, model):
        h.update(Path(mod.__file__).read_bytes())
    h.update(Path(__file__).read_bytes())
    return h.hexdigest()


def digest(sc: Scenario, config: PhysicsConfig, fid: Fidelity, sampling: Sampling) -> str:
    """What the model depends on: the scenario's content, the physics config, the fidelity,
    the sampling, the batch size (which robot slot, so which noise stream, drives what),
    pymunk and the source of the world's code."""
    fields = {k: v for k, v in dataclasses.asdict(sc).items()
              if k not in ("name", "source", "description", "rewards", "physics",
                           "s_start_share")}
    blob = json.dumps([FORMAT, pymunk.version, _code_digest(), fields,
                       dataclasses.asdict(config), dataclasses.asdict(fid),
                       dataclasses.asdict(sampling), BATCH], sort_keys=True, default=repr)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


# every array of the model and its dtype, then its scalars (stored as 0-d arrays)
_ARRAYS = {"state_cell": np.int32, "state_context": np.int8, "state_pose": np.float64,
           "sa_ptr": np.int64, "dst": np.int32, "prob": np.float64, "mean_steps": np.float64}
_SCALARS = ("nx", "ny", "cell_m", "start_cell", "goal_cell", "primitives", "build_s", "timeouts")
CACHE = disk_cache.CacheKind("stochastic-model", FORMAT, (*_ARRAYS, *_SCALARS),
                             "stochastic-model")
MAX_CACHE_BYTES = 4 * 1024 ** 3  # far beyond any model a build can drive in a day


def _arrays(m: StochasticModel) -> disk_cache.Arrays:
    return {**{a: getattr(m, a) for a in _ARRAYS},
            **{s: np.array(getattr(m, s)) for s in _SCALARS}}


def _check(a: disk_cache.Arrays, sc: Scenario) -> str | None:
    """Why cached arrays cannot be the model of ``sc``, or None: every dtype and shape, the
    scenario's size and its S and G, indices in range, probabilities in (0, 1]."""
    if any(a[k].dtype != t for k, t in _ARRAYS.items()) or any(a[k].shape for k in _SCALARS):
        return "an array has the wrong dtype or shape"
    disc = Discretiser.from_scenario(sc)
    if (a["nx"].item(), a["ny"].item(), a["cell_m"].item(), a["start_cell"].item(),
            a["goal_cell"].item()) != (sc.nx, sc.ny, sc.cell_size_m, disc.index(*sc.start),
                                       disc.index(*sc.goal)):
        return "it was built for another arena"
    n = a["state_cell"].size
    ptr, dst, prob = a["sa_ptr"], a["dst"], a["prob"]
    if not (a["state_cell"].shape == a["state_context"].shape == (n,)
            and a["state_pose"].shape == (n, 4) and ptr.shape == (N_ACTIONS * n + 1,)
            and a["mean_steps"].shape == (n, N_ACTIONS) and dst.ndim == 1
            and dst.shape == prob.shape):
        return "its arrays' shapes do not fit together"
    cells, ctx = a["state_cell"], a["state_context"]
    if not (ptr[0] == 0 and ptr[-1] == dst.size and bool(np.all(np.diff(ptr) >= 1))
            and (n == 0 or (cells.min() >= 0 and cells.max() < sc.nx * sc.ny
                            and ctx.min() >= 0 and ctx.max() < N_CONTEXTS))
            and (dst.size == 0 or (dst.min() >= 0 and dst.max() <= n))
            and bool(np.all((prob > 0) & (prob <= 1)))
            and min(a["primitives"].item(), a["timeouts"].item()) >= 0):
        return "an index or a probability is out of range"
    return None


@lru_cache(maxsize=8)
def stochastic_model(sc: Scenario, fidelity: Fidelity | None = None,
                     sampling: Sampling | None = None,
                     config: PhysicsConfig | None = None) -> StochasticModel:
    """The driven model of ``sc`` at ``fidelity`` (cached in-process and on disk)."""
    fid = fidelity or Fidelity()
    refuse_hidden_state(fid)
    config = config or PhysicsConfig()
    sampling = sampling or Sampling.default(fid)
    sampling.validate()
    a = disk_cache.cached(
        CACHE, digest(sc, config, fid, sampling),
        lambda: _arrays(build_stochastic_model(sc, fid, sampling, config)),
        lambda got: _check(got, sc), max_bytes=MAX_CACHE_BYTES)
    return StochasticModel(fidelity=fid, sampling=sampling,
                           **{k: a[k] for k in _ARRAYS},
                           **{k: a[k].item() for k in _SCALARS})

"""The physics training step as one compiled call: act, the primitive's physics, the
outcome and reward, the update, episode ends and new starts, for every run of a group.

The batched loop (:func:`scenarios.runs.physics.train_physics_runs`) made a Python round
trip per primitive of every robot: a compiled call to act for each method, the world's
step (its arguments, a kernel call, an outcome pass, the env's rules in numpy, its info
dict), a compiled call to update. At ``exact`` that was four fifths of a primitive's cost
(the kernel alone is about 1 us). Here one compiled call per group of runs (one method,
one learner type: numba compiles it once per method) drives each run robot by robot until
it needs Python: a periodic greedy test is due (the run's learner is left as it ended the
episode), its episodes are all done, Chipmunk must settle a contact the compiled narrow
phase cannot be sure of (``CHECK``), or the call's budget of primitives is spent (so
Ctrl-C, progress and queued tests are served within a bounded time).

Each run is the run of the batched loop, draw for draw: the same hooks act and learn on
its row of the stacked state with its own learner stream
(:mod:`learning.drivers.batch_agent`), its starts come from its start stream
(:func:`learning.compiled.hooks.draw_start`), its robot is placed and driven by the
kernel's own functions (:func:`sim.physics.kernel.primitive.begin_one`,
:func:`~sim.physics.kernel.primitive.advance_one`), its wheel noise refilled from its noise
stream in its block layout (:func:`sim.physics.kernel.noise.refill`), and the reward is the
env's rule (:func:`sim.scenario.move_reward`, the same function inlined). Tested: per-run
logs, tests and learned tables equal to the batched loop's at ``exact`` and above it.

Wall time: a call's time is shared evenly among the primitives it drove (the batched loop
shared a step's time among the robots it advanced).
"""

from __future__ import annotations

import hashlib
import os
import time
from pathlib import Path
from types import FunctionType, ModuleType
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from learning.compiled import hooks
from learning.compiled.generator_handle import HANDLE_SIZE, generator_from
from learning.compiled.hooks import act, begin, update  # stand-ins: see fused_driver
from learning.compiled.kernels import compiled_for
from learning.compiled.named_state import row
from learning.compiled.pipeline import TemplateCompiler, read_once
from learning.compiled.state_box import box_of
from learning.jitcache import restamp
from learning.jitcache import sources_digest as learning_digest
from sim.grid.actions import N_ACTIONS
from sim.physics.drive_profiles import Profiles
from sim.physics.jitcache import sources_digest as physics_digest
from sim.physics.kernel.noise import refill_one
from sim.physics.kernel.primitive import advance_one, begin_one
from sim.physics.kernel.state import BORROWS, Geometry, Params, Scratch, Status
from sim.scenario import move_reward

_move_reward = njit(inline="always")(move_reward)  # the env's rule, this very function

STAMP = "physics-fused-sources.sha256"


_REWARD_RULE = Path(__file__).resolve().parents[2] / "sim" / "scenario.py"  # inlined too


class Rules(NamedTuple):
    """The route problem's rules as the compiled loop reads them."""

    goal_state: int  # G's state index
    goal_reward: float  # entering G
    bump_reward: float  # a contact began
    step_reward: float  # any other move
    steps_per_episode: int  # primitives before an episode is cut off
    physics_step_s: float  # the physics step [s] (simulated time)


def drop_stale_cache(module: Path | None = None) -> bool:
    """Delete this module's numba cache when its sources changed: :func:`drive_runs` inlines
    every method's hooks (``learning``) and the kernel's stepping (``sim.physics``), and numba
    keys a cached function on its own file only, so after an upgrade that moved a learner's
    module the cached call would import a module that is gone (seen) or run old rules. The
    stamp is a hash of both packages' sources and this file; the primitive's read-once copy
    goes with it. True if it dropped the cache;
    with ``NUMBA_CACHE_DIR`` set the cache is left alone (as the packages' own guards do).
    ``module``: this file (another, for tests)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return False
    here = (module or Path(__file__)).resolve()
    cache = here.parent / "__pycache__"
    digest = hashlib.sha256((learning_digest() + physics_digest()).encode()
                            + here.read_bytes() + _REWARD_RULE.read_bytes()).hexdigest()
    copies = Path(advance_one.py_func.__code__.co_filename).parent / "__pycache__"
    return restamp(cache, STAMP, digest, lambda: [
        *cache.glob(f"{here.stem}.*.nbi"), *cache.glob(f"{here.stem}.*.nbc"),
        # the primitive's read-once copy (below) is cached beside the primitive, and
        # compiled by learning's pass: sim's own guard does not see that pass change
        *copies.glob("*_read_once-*.nbi"), *copies.glob("*_read_once-*.nbc")])


drop_stale_cache()
# the primitive's loop reads the world's named tuples at every control period: read once
# (and, as the primitive itself, without reference counting: BORROWS)
ADVANCE_ONE = read_once(advance_one, **BORROWS)
ACT, MOVE, START, TEST, FINISHED, BAD = 0, 1, 2, 3, 4, 5  # where a run stands between calls
CALL_PRIMITIVES = 16384  # primitives a call drives at most, shared among its runs: a call
#                          then takes ~15-50 ms (1-3 us a primitive; haql cut off in a noisy
#                          world ~15 us), the bound on answering Ctrl-C and progress


def drive_runs(box, learner_h, start_h, starts, robots, blank, noise, npos, nend, nblock,
               noise_h, traj, contacts, booked, pt, prof_t, geo_t, st, bias, rules, mine,
               stage, s, a, t, ret, ncontact, done, wall, callp, logs_i, logs_f, n_episodes,
               test_every, budget):
    """Drive every run ``i`` with ``mine[i]`` until it needs Python (see the module).

    ``rules``: the route problem's :class:`Rules`. Per-episode logs: ``logs_i`` int64[3, n,
    episodes] (steps, contacts, primitives of the episode driven in this call), ``logs_f``
    float64[6, n, episodes] (return, success, shaping mean, shaping std, wall [s] before this call,
    simulated time [s]). Returns (primitives driven, episodes ended, runs waiting on a
    Chipmunk check).

    A template, compiled per method by :func:`fused_driver`: ``act``, ``update`` and
    ``begin`` are the method's own hooks, inlined, so the loop has no call between a
    primitive and its learner (as a call, each hook took and dropped a reference to each of
    the row's thirty-odd arrays, twice a primitive).
    """
    stt = box.state
    p, prof, g, sc = Params(*pt), Profiles(*prof_t), Geometry(*geo_t), Scratch(*st)
    goal, max_steps, dt = rules.goal_state, rules.steps_per_episode, rules.physics_step_s
    prims = ended = checks = 0
    for i in range(robots.shape[0]):
        callp[i] = 0
        if not mine[i]:
            continue
        rb = robots[i]
        sti = row(stt, i)  # once per run and call: a row is a view of every array, each
        #                    view a reference counted (two atomic operations) when made
        left = budget
        while left > 0:
            k = stage[i]
            if k == START:
                s0 = hooks.draw_start(generator_from(start_h[i]), starts)
                s[i] = s0
                begin(sti, s0)
                robots[i] = blank[0]
                rb.x = rb.bx = (s0 % p.nx + 0.5) * p.cell_m
                rb.y = rb.by = (s0 // p.nx + 0.5) * p.cell_m
                rb.gain_l, rb.gain_r, rb.base_k = bias[i, 0], bias[i, 1], bias[i, 2]
                booked[i] = 0
                t[i], ret[i], ncontact[i], wall[i], callp[i] = 0, 0.0, 0, 0.0, 0
                stage[i] = ACT
            elif k == ACT:
                a[i] = act(sti, s[i], generator_from(learner_h[i]))
                if a[i] < 0 or a[i] >= N_ACTIONS:  # a learner of the user's: Python says
                    stage[i] = BAD
                    break
                begin_one(rb, a[i], p.cell_m, p.nx, p.ny, p.localisation)
                stage[i] = MOVE
            elif k == MOVE:
                ADVANCE_ONE(i, robots, noise, npos, nend, traj, contacts, booked, p, prof, g,
                            sc)
                if rb.status == Status.NOISE:
                    refill_one(i, noise, npos, nend, nblock, noise_h)
                    continue
                if rb.status != Status.DONE:  # CHECK: Chipmunk decides, then call again
                    checks += 1
                    break
                booked[i] = 0
                prims += 1
                left -= 1
                callp[i] += 1
                s2 = rb.state
                terminated = rb.tstate == goal  # the true cell (s2: the believed one)
                r = _move_reward(rules.goal_reward, rules.bump_reward, rules.step_reward,
                                 terminated, rb.bumped, True)
                t[i] += 1
                ret[i] += r
                ncontact[i] += rb.ncontact
                update(sti, s[i], a[i], r, s2, terminated, generator_from(learner_h[i]))
                s[i] = s2
                if not (terminated or t[i] >= max_steps):
                    stage[i] = ACT
                    continue
                hooks.end(sti)
                e = done[i]
                logs_i[0, i, e], logs_i[1, i, e], logs_i[2, i, e] = t[i], ncontact[i], callp[i]
                logs_f[0, i, e], logs_f[1, i, e] = ret[i], 1.0 if terminated else 0.0
                logs_f[2, i, e], logs_f[3, i, e] = hooks.shaping(sti)
                logs_f[4, i, e], logs_f[5, i, e] = wall[i], rb.steps * dt
                done[i] = e + 1
                ended += 1
                callp[i] = 0
                if done[i] % test_every == 0 or done[i] == n_episodes:
                    stage[i] = TEST
                    break
                stage[i] = START
            else:  # TEST, FINISHED or BAD: Python's turn
                break
    return prims, ended, checks


def fused_driver(st: Any) -> Any:
    """:func:`drive_runs` compiled for the method of the stacked state ``st``, its hooks
    inlined (:func:`learning.compiled.kernels.compiled_for`: one dispatcher per method,
    all cached in this file's cache under the template's name, told apart by the state's
    class in the signature; :func:`drop_stale_cache` guards them)."""
    return compiled_for(drive_runs, st)


# ------------------------------------------------------------------ a @jitclass learner's runs

@njit(inline="always")
def _nth(learners, i):
    return learners[i]


@njit(inline="always")
def _jit_act(learner, s, rng):  # rng: unread (a jitclass draws from its own field)
    return learner.act(s)


@njit(inline="always")
def _jit_update(learner, s, a, r, s2, terminated, rng):
    learner.update(s, a, r, s2, terminated)


@njit(inline="always")
def _jit_start(learner, s0):
    learner.episode_start()


@njit(inline="always")
def _jit_no_start(learner, s0):
    pass


@njit(inline="always")
def _jit_end(learner):
    pass


@njit(inline="always")
def _jit_shaping(learner):
    return 0.0, 0.0  # a plain learner shapes nothing the loop could read


_JIT_DRIVERS: dict[bool, Any] = {}


def jit_driver(with_start: bool) -> Any:
    """:func:`drive_runs` for runs of a plain learner written as a ``@jitclass``: the same
    source, compiled with the learner's own ``act``, ``update`` and (``with_start``)
    ``episode_start`` as its hooks and the run's learner as its row (a typed list of the
    runs' learners behind the box). Compiled without numba's on-disk cache, as the grid's
    loop (:mod:`learning.plain.compiled`), so a class edited under the same name never meets
    a stale kernel; once per process and kind of class."""
    fn = _JIT_DRIVERS.get(with_start)
    if fn is None:
        jit_hooks = ModuleType("jit_learner_hooks")
        jit_hooks.draw_start = hooks.draw_start
        jit_hooks.end, jit_hooks.shaping = _jit_end, _jit_shaping
        names = dict(drive_runs.__globals__, hooks=jit_hooks, row=_nth, act=_jit_act,
                     update=_jit_update, begin=_jit_start if with_start else _jit_no_start)
        fn = _JIT_DRIVERS[with_start] = njit(cache=False, pipeline_class=TemplateCompiler)(
            FunctionType(drive_runs.__code__, names, "drive_jit_runs"))
    return fn


_BOX_OF: Any = None


def jit_box(learners: list[Any]) -> tuple[Any, np.ndarray]:
    """The runs' jitclass learners as :func:`jit_driver` reads them: behind one box a typed
    list holding the same objects (the loop's updates are the Python objects'), boxed
    without numba's on-disk cache; and the learner-stream handles the loop's signature
    takes (unread: a jitclass draws from its own field)."""
    from numba.typed import List

    global _BOX_OF
    if _BOX_OF is None:
        _BOX_OF = njit(cache=False)(box_of.py_func)
    return _BOX_OF(List(learners)), np.zeros((len(learners), HANDLE_SIZE), np.uint64)


class FusedRuns:
    """The runs of one group (``rows`` of its :class:`BatchAgent`) driven by
    :func:`drive_runs`; robots ``b0 + k`` of ``batch``. The loop's per-run arrays (``s``,
    ``t``, ``ret``, ``contacts``, ``done``, ``wall``: views of the group's slice) are
    shared with the caller, who placed every robot and began its episode."""

    def __init__(self, agent: Any, rows: np.ndarray, b0: int, batch: Any, start_h: np.ndarray,
                 starts: np.ndarray, rules: Rules, n_episodes: int, test_every: int,
                 loop: dict[str, np.ndarray], driver: Any = None) -> None:
        n = agent.n
        self._drive = fused_driver(agent.states) if driver is None else driver  # (or a
        #                                                        jitclass learner's own)
        self.agent, self.b0, self.batch, self.n_episodes = agent, b0, batch, n_episodes
        sl = slice(b0, b0 + n)
        self.mine = np.zeros(n, np.bool_)
        self.mine[rows] = True
        self.stage = np.where(self.mine, ACT, FINISHED).astype(np.int64)
        self.loop = {k: v[sl] for k, v in loop.items()}
        self.logs_i = np.zeros((3, n, n_episodes), np.int64)
        self.logs_f = np.zeros((6, n, n_episodes))
        self.callp = np.zeros(n, np.int64)
        box, handles = (jit_box(agent.learners) if getattr(agent, "jit", False)
                        else (agent._box, agent._handles))
        self._args = [box, handles, start_h, starts, batch.robots[sl],
                      np.zeros(1, batch.robots.dtype), batch._noise[sl], batch._npos[sl],
                      batch._nend[sl], batch._nblock[sl], batch._noise_h[sl], batch._traj[sl],
                      batch._booked_rows[sl], batch._booked[sl], *batch._args,
                      batch._bias[sl], rules, self.mine, self.stage]
        budget = max(16, CALL_PRIMITIVES // max(len(rows), 1))  # per run
        self._tail = (self.callp, self.logs_i, self.logs_f, n_episodes, test_every, budget)

    @property
    def live(self) -> bool:
        """Some run of the group has episodes left."""
        return bool((self.stage != FINISHED).any())

    def drive(self) -> tuple[list[int], int, int]:
        """One call: (the group's rows whose greedy test is due, primitives, episodes ended).
        Chipmunk's checks are answered here; the caller runs the tests, then
        :meth:`tested`."""
        lp = self.loop
        done0 = lp["done"].copy()
        t0 = time.perf_counter()
        prims, ended, checks = self._drive(
            *self._args, lp["s"], lp["a"], lp["t"], lp["ret"], lp["contacts"], lp["done"],
            lp["wall"], *self._tail)
        for k in np.flatnonzero(self.stage == BAD):  # raises, naming the learner
            self.agent.refuse_action(int(k), int(lp["s"][k]), int(lp["a"][k]))
        rate = (time.perf_counter() - t0) / max(prims, 1)
        lp["wall"][self.mine] += self.callp[self.mine] * rate  # episodes under way
        for k in np.flatnonzero(lp["done"] != done0):  # episodes ended: their share
            e0, e1 = int(done0[k]), int(lp["done"][k])
            self.logs_f[4, k, e0:e1] += self.logs_i[2, k, e0:e1] * rate
        if checks:
            status = self.batch.r.status[self.b0:self.b0 + self.agent.n]
            for k in np.flatnonzero(self.mine & (status == int(Status.CHECK))):
                self.batch._check(self.b0 + int(k))
        return np.flatnonzero(self.stage == TEST).tolist(), prims, ended

    def tested(self, k: int) -> None:
        """Row ``k``'s test is done: it starts its next episode, or is finished."""
        done = int(self.loop["done"][k])
        self.stage[k] = FINISHED if done >= self.n_episodes else START

    def write_logs(self, logs: Any) -> None:
        """The group's fused runs' per-episode logs into the loop's (:class:`_Logs`)."""
        for k in np.flatnonzero(self.mine):
            i, e = self.b0 + int(k), int(self.loop["done"][k])
            li, lf = self.logs_i[:, k, :e], self.logs_f[:, k, :e]
            logs.steps[i, :e], logs.contacts[i, :e] = li[0], li[1]
            logs.returns[i, :e], logs.success[i, :e] = lf[0], lf[1] > 0.0
            logs.shaping_mean[i, :e], logs.shaping_std[i, :e] = lf[2], lf[3]
            logs.wall[i, :e], logs.sim_time[i, :e] = lf[4], lf[5]

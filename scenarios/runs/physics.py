"""Training and driving in the physics world (``--world physics``).

The learner is the step-by-step agent (:mod:`learning.agent`) on
``rnhql/PhysicsRoute-v0``: the same update rules as the grid kernels, states
from the discretised pose, bumps from real contacts.

Greedy tests every ``test_every`` episodes evaluate the learned policy on the
*physics world's own* tabular model (:func:`sim.physics.model.physics_model`:
each primitive driven once from each reachable cell centre, cached), against
the physics optimum: the real disc can enter cells the grid's clearance blocks,
so grading on the grid model would call a route through them "no G". The
record keeps both optima (``grid_optimal_route_length``,
``physics_optimal_route_length``). The final greedy route is then also *driven*
in physics, which gives the continuous figures (metres, contacts, sim time).
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

import sim.envs  # noqa: F401  (registers the ids)
from learning.agent import StepAgent, make_agent, run_env_episodes
from learning.geometry import geometry_of
from learning.metrics import episodes_to_first_optimal
from learning.train import greedy_test, shortest_fraction
from sim.grid import TabularModel
from sim.scenario import Scenario


class ContactCounter(gym.Wrapper):
    """Counts contacts and sim time per episode from the physics env's ``info``."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.contacts: list[int] = []
        self.sim_time_s: list[float] = []
        self._c, self._t, self._active = 0, 0.0, False

    def reset(self, **kwargs: Any):
        self.flush()
        return self.env.reset(**kwargs)

    def step(self, action: int):
        obs, r, term, trunc, info = self.env.step(action)
        self._c += len(info["contacts"])
        self._t, self._active = info["time_s"], True
        return obs, r, term, trunc, info

    def flush(self) -> None:
        """Close the running episode's counts (called by reset, and once at the end)."""
        if self._active:
            self.contacts.append(self._c)
            self.sim_time_s.append(self._t)
        self._c, self._t, self._active = 0, 0.0, False


def continuous_optimum_rounded(sc: Scenario) -> float | None:
    """The disc's any-angle S-G path length [m] (:mod:`sim.physics.optimum`), for records."""
    from sim.physics.optimum import continuous_optimum_m

    v = continuous_optimum_m(sc)
    return None if v is None else round(v, 4)


@dataclass
class DrivenRoute:
    """A greedy policy driven from S in physics."""

    states: list[int]
    trajectory: np.ndarray  # (n, 3) poses of every substep [m, m, rad]
    reached: bool
    contacts: int
    sim_time_s: float
    metres: float  # path length driven [m]
    poses: np.ndarray  # (len(states), 3): the pose after each primitive [m, m, rad]

    def extras(self) -> dict[str, Any]:
        xy = np.round(self.trajectory[::2, :2], 3)
        return {"physics_route_length": len(self.states) - 1 if self.reached else -1,
                "physics_route_xy": xy.tolist(),
                "physics_route_metres": round(self.metres, 4),
                "physics_route_contacts": self.contacts,
                "physics_route_sim_time_s": round(self.sim_time_s, 4)}


def drive_greedy(agent_or_policy: Any, sc: Scenario, max_steps: int | None = None,
                 fidelity: Any = None) -> DrivenRoute:
    """Drive the greedy policy (a StepAgent or ``policy(s) -> a``) from S in a fresh world
    (at ``fidelity``; its noise from the env's stream seeded 0, the same for every run)."""
    policy = (agent_or_policy.greedy_action if isinstance(agent_or_policy, StepAgent)
              else agent_or_policy)
    env = gym.make("rnhql/PhysicsRoute-v0", scenario=sc, fidelity=fidelity,
                   max_episode_steps=max_steps or sc.steps_per_episode)
    s, info = env.reset(seed=0)
    states, traj, poses = [int(s)], [info["trajectory"]], [info["pose"]]
    contacts, term, trunc = 0, False, False
    while not (term or trunc):
        s, _, term, trunc, info = env.step(policy(int(s)))
        states.append(int(s))
        traj.append(info["trajectory"])
        poses.append(info["pose"])
        contacts += len(info["contacts"])
    pts = np.concatenate(traj)
    # per primitive: after a bump the robot is *placed* back, and that jump is not driven
    metres = float(sum(np.hypot(*np.diff(t[:, :2], axis=0).T).sum() for t in traj))
    env.close()
    return DrivenRoute(states, pts, bool(term), contacts, float(info["time_s"]), metres,
                       np.asarray(poses, dtype=np.float64))


@dataclass(eq=False)
class PhysicsTrainResult:
    """The fields :func:`scenarios.experiment.run_record` reads, for a physics run."""

    agent: StepAgent
    steps: np.ndarray
    returns: np.ndarray
    success: np.ndarray
    shaping_mean: np.ndarray
    shaping_std: np.ndarray
    wall_time_s: np.ndarray
    test_episodes: np.ndarray
    test_route_length: np.ndarray
    optimal_length: int
    final_route: list[int]
    final_route_length: int
    optimal_action_fraction: float
    driven: DrivenRoute
    graded: TabularModel  # the model the greedy tests ran on (the physics world's own)
    world_extras: dict[str, Any] = field(default_factory=dict)

    @property
    def episodes_to_optimal(self) -> int | None:
        return episodes_to_first_optimal(self.test_episodes, self.test_route_length,
                                  self.optimal_length)


class _StopAtStep(gym.Wrapper):
    """Ctrl-C during physics training is raised here, between env steps, never elsewhere.

    A SIGINT delivered while Python is inside a numba call's argument handling (the
    step agent passes its ``numpy.random.Generator`` on every update) or inside a
    Chipmunk callback crashes the process (SIGSEGV) or is lost. While training runs,
    the signal only sets a flag; this wrapper raises ``KeyboardInterrupt`` at the next
    ``step``/``reset``, in plain Python. A second Ctrl-C exits at once (status 130).
    """

    def __init__(self, env: Any) -> None:
        super().__init__(env)
        self.requested = False

    def request(self, _sig: int, _frame: Any) -> None:
        if self.requested:
            os._exit(130)
        self.requested = True

    def _check(self) -> None:
        if self.requested:
            raise KeyboardInterrupt

    def step(self, action: Any) -> Any:
        out = self.env.step(action)
        self._check()
        return out

    def reset(self, **kwargs: Any) -> Any:
        self._check()
        return self.env.reset(**kwargs)


@contextlib.contextmanager
def sigint_to(stopper: Any) -> Iterator[None]:
    """SIGINT goes to ``stopper.request`` while the block runs (main thread only)."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is signal.SIG_IGN:  # e.g. a pool worker
        yield
        return
    old = signal.signal(signal.SIGINT, stopper.request)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def train_physics(cfg: Any, sc: Scenario, model: TabularModel, n_episodes: int,
                  rng: np.random.Generator, test_every: int = 10,
                  recorder: Any = None, plan: Any = None,
                  start_rng: np.random.Generator | None = None, fidelity: Any = None,
                  noise_rng: np.random.Generator | None = None) -> PhysicsTrainResult:
    """Train the step agent in PhysicsRoute-v0; optionally record (see recorded_runs).

    ``rng`` is the learner's stream, ``start_rng`` the start cells' (default ``rng``):
    with :func:`learning.streams.streams` a grid run and a physics run of one seed
    start their episodes in the same cells.
    """
    from scenarios.recording.hooks import EpisodeTap

    inner = gym.make("rnhql/PhysicsRoute-v0", scenario=sc, fidelity=fidelity,
                     max_episode_steps=sc.steps_per_episode)
    if noise_rng is not None:
        inner.unwrapped.set_noise_rng(noise_rng)
    counter = ContactCounter(inner)
    env = EpisodeTap(counter)
    stopper = _StopAtStep(env)
    with sigint_to(stopper):
        return _train(cfg, sc, model, n_episodes, rng, test_every, recorder, plan, start_rng,
                      counter, env, stopper, fidelity)


def _train(cfg: Any, sc: Scenario, model: TabularModel, n_episodes: int,
           rng: np.random.Generator, test_every: int, recorder: Any, plan: Any,
           start_rng: np.random.Generator | None, counter: Any, env: Any,
           stopper: _StopAtStep, fidelity: Any = None) -> PhysicsTrainResult:
    from scenarios.recording.hooks import ChunkLogger
    from sim.physics.model import physics_model

    graded = physics_model(sc)  # the physics world's own transitions and optimum
    agent = make_agent(cfg, geometry_of(model), rng)
    views = ChunkLogger(recorder, plan) if recorder is not None else None
    logs, walls, tests_e, tests_l = [], [], [], []
    done = 0
    while done < n_episodes:
        n = min(test_every, n_episodes - done)
        # segments of the chunk: each recorded episode alone, the rest together
        marks = [plan is not None and plan.wants(done + i) for i in range(n)]
        i = 0
        while i < n:
            j = i + 1 if marks[i] else next((k for k in range(i, n) if marks[k]), n)
            env.armed = marks[i]
            t0 = time.perf_counter()
            logs.append(run_env_episodes(agent, stopper, j - i, start_rng))
            walls.append(np.full(j - i, (time.perf_counter() - t0) / (j - i)))
            if marks[i] and recorder is not None:
                env.log_to(recorder, done + i)
            i = j
        done += n
        test = greedy_test(agent.state, graded)
        tests_e.append(done)
        tests_l.append(test[0])
        if views is not None:
            arrays = {k: np.concatenate([getattr(lg, k) for lg in logs])
                      for k in ("steps", "returns", "success", "shaping_mean", "shaping_std")}
            arrays["wall_time_s"] = np.concatenate(walls)
            views.after_chunk(done, arrays, agent.state, test[1])
    counter.flush()
    env.close()
    length, route = greedy_test(agent.state, graded)
    driven = drive_greedy(agent, sc, fidelity=fidelity)
    cat = {k: np.concatenate([getattr(lg, k) for lg in logs])
           for k in ("steps", "returns", "success", "shaping_mean", "shaping_std")}
    extras = {"grid_optimal_route_length": model.optimal_route_length,
              "physics_optimal_route_length": graded.optimal_route_length,
              "continuous_optimal_route_m": continuous_optimum_rounded(sc),
              "contacts_per_episode": counter.contacts[-n_episodes:],
              "sim_time_per_episode_s": np.round(counter.sim_time_s[-n_episodes:], 4).tolist(),
              **driven.extras()}
    return PhysicsTrainResult(agent=agent, **cat, wall_time_s=np.concatenate(walls),
                              test_episodes=np.asarray(tests_e),
                              test_route_length=np.asarray(tests_l),
                              optimal_length=graded.optimal_route_length, final_route=route,
                              final_route_length=length,
                              optimal_action_fraction=shortest_fraction(agent.state, graded),
                              driven=driven, graded=graded, world_extras=extras)

"""``--record``: connect training runs to :mod:`scenarios.recording.recorder`.

Which episodes are recorded in full (``--record-every N``): the first, every
N-th, the last, and every greedy test from S. Curves are logged for every
episode, value heat maps every ``values_every`` episodes. In the grid world
the fused kernel writes the states of the chunks that hold a recorded episode
into a trace buffer (one store per step, no draws, so a recorded run equals
an unrecorded one); in physics an env wrapper taps poses, contacts and sim
time from ``info`` while a recorded episode runs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from learning.readout import greedy_actions, potential, q_table
from scenarios.recording.recorder import Recorder


@dataclass(frozen=True)
class RecordPlan:
    n_episodes: int  # episodes in the run
    every: int = 10  # record every N-th episode in full (plus the first and the last)
    values_every: int = 300  # value heat maps (and a batch of curves) every K episodes
    detail: bool = True  # False: curves only (no trajectories, greedy tests or heat maps)

    def wants(self, episode: int) -> bool:
        return self.detail and (episode == 0 or episode == self.n_episodes - 1
                                or episode % self.every == 0)

    def wanted(self, first: int, n: int) -> list[int]:
        """The episodes in ``first .. first + n - 1`` recorded in full (no per-episode loop:
        this runs after every chunk of a 0.06 ms/episode kernel)."""
        if not self.detail or n <= 0:
            return []
        eps = set(range(first + (-first) % self.every, first + n, self.every))
        eps.update(e for e in (0, self.n_episodes - 1) if first <= e < first + n)
        return sorted(eps)

    def wants_values(self, episodes_done: int) -> bool:
        return episodes_done % self.values_every == 0 or episodes_done == self.n_episodes


def log_chunk_metrics(rec: Recorder, first: int, n: int, arrays: dict[str, np.ndarray]) -> None:
    sl = slice(first, first + n)
    steps = arrays["steps"][sl]
    rec.log_episode_metrics(np.arange(first, first + n), steps, arrays["success"][sl],
                            arrays["returns"][sl],
                            wall_time_s=arrays["wall_time_s"][sl],
                            shaping_mean=arrays["shaping_mean"][sl],
                            shaping_std=arrays["shaping_std"][sl])


class ChunkLogger:
    """What every chunk logs: its greedy test; every ``values_every`` episodes, the
    curves of the episodes since the last batch and the value heat maps.

    Curves go out in batches (one call per ``values_every`` episodes): with
    0.06 ms training episodes, a call per 10-episode chunk cost 25 % extra time.
    """

    def __init__(self, rec: Recorder, plan: RecordPlan, first_episode: int = 0) -> None:
        self.rec, self.plan, self.logged = rec, plan, first_episode

    def after_chunk(self, done: int, arrays: dict[str, np.ndarray], st,
                    test_route: list[int]) -> None:
        if self.plan.detail:
            self.rec.log_episode_trajectory(done - 1, np.asarray(test_route),
                                            kind="greedy-test")
        if self.plan.wants_values(done):
            log_chunk_metrics(self.rec, self.logged, done - self.logged, arrays)
            self.logged = done
            if self.plan.detail:
                self.rec.log_values(done - 1, q_table(st), greedy_actions(st), potential(st))


class GridRecorder:
    """A :class:`learning.train.TrainObserver` that records a fused-kernel run."""

    def __init__(self, rec: Recorder, plan: RecordPlan) -> None:
        self.rec, self.plan = rec, plan
        self.views = ChunkLogger(rec, plan)

    def trace_chunk(self, first_episode: int, n: int) -> bool:
        return bool(self.plan.wanted(first_episode, n))

    def after_chunk(self, first_episode: int, n: int, trace: np.ndarray | None,
                    arrays: dict[str, np.ndarray], state,
                    test: tuple[int, list[int]]) -> None:
        if trace is not None:
            steps = arrays["steps"]
            for ep in self.plan.wanted(first_episode, n):
                k = int(steps[ep])
                self.rec.log_episode_trajectory(ep, trace[ep - first_episode, :k + 1],
                                                kind="train")
        self.views.after_chunk(first_episode + n, arrays, state, test[1])


class EpisodeTap(gym.Wrapper):
    """Captures states, poses, sim time and contact points of an episode while ``armed``."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.armed = False
        self._clear()

    def _clear(self) -> None:
        self.states: list[int] = []
        self.poses: list[tuple[float, float, float]] = []
        self.times: list[float] = []
        self.contacts: list[tuple[float, float]] = []
        self.contact_steps: list[int] = []
        self.substeps: list[np.ndarray] = []  # every physics step's pose, per primitive
        self.substep_times: list[np.ndarray] = []

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        self._clear()
        if self.armed:
            self.states.append(int(obs))
            self.poses.append(info["pose"])
            self.times.append(info["time_s"])
        return obs, info

    def step(self, action: int):
        obs, r, term, trunc, info = self.env.step(action)
        if self.armed:
            traj = np.asarray(info["trajectory"], dtype=np.float64).reshape(-1, 3)
            if len(traj):  # the continuous drive, its times spread over the primitive
                t0 = self.times[-1] if self.times else 0.0
                self.substeps.append(traj)
                self.substep_times.append(np.linspace(t0, info["time_s"], len(traj) + 1)[1:])
            self.states.append(int(obs))
            self.poses.append(info["pose"])
            self.times.append(info["time_s"])
            for c in info["contacts"]:
                self.contacts.append((c.x_m, c.y_m))
                self.contact_steps.append(len(self.states) - 1)
        return obs, r, term, trunc, info

    def log_to(self, rec: Recorder, episode: int) -> None:
        if not self.states:
            return
        rec.log_episode_trajectory(
            episode, np.asarray(self.states), poses=np.asarray(self.poses),
            contacts=np.asarray(self.contacts).reshape(-1, 2),
            sim_time_s=np.asarray(self.times), kind="train",
            contact_steps=np.asarray(self.contact_steps, dtype=np.int64),
            substeps=(np.concatenate(self.substeps) if self.substeps else None),
            substep_times_s=(np.concatenate(self.substep_times) if self.substeps else None))

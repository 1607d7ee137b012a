"""``--record``: connect training runs to :mod:`scenarios.recording.recorder`.

Which episodes are recorded in full (``--record-every N``): the first, every
N-th, the last, and every greedy test from S. Curves are logged for every
episode, value heat maps every ``values_every`` episodes. In the grid world
the fused kernel writes the states of the chunks that hold a recorded episode
into a trace buffer (one store per step, no draws, so a recorded run equals
an unrecorded one); in physics a vector-env wrapper taps the recorded runs' sub-envs
(poses, contacts, sim time, every physics step) while a recorded episode runs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium.vector import VectorWrapper

from learning.compiled.readout import greedy_actions, potential, q_table
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
    """A :class:`learning.drivers.train.TrainObserver` that records a fused-kernel run."""

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


class EpisodeTaps(VectorWrapper):
    """Taps sub-envs of a :class:`sim.physics.envs.vector.PhysicsRouteVectorEnv`: while sub-env
    ``i`` is armed (:meth:`arm`, at the start of an episode to record in full), its states,
    poses, sim time, contact points and every physics step's pose are kept, for
    :meth:`log_to`. Untapped sub-envs cost nothing; the env must keep trajectories."""

    def __init__(self, env: Any, indices: list[int]) -> None:
        super().__init__(env)
        self.taps = {int(i): _Tap() for i in indices}

    def arm(self, i: int, on: bool) -> None:
        """Record sub-env ``i``'s next episode in full (or not); clears what it held."""
        self.taps[i] = _Tap(armed=on)

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        mask = (options or {}).get("reset_mask")
        for i, tap in self.taps.items():
            if tap.armed and (mask is None or mask[i]):
                tap.states.append(int(obs[i]))
                tap.poses.append(tuple(info["pose"][i]))
                tap.times.append(float(info["time_s"][i]))
        return obs, info

    def step(self, actions: Any):
        obs, r, term, trunc, info = self.env.step(actions)
        base = self.env.unwrapped
        for i, tap in self.taps.items():
            if not (tap.armed and info["_steps"][i]):
                continue
            traj = base.trajectory(i)
            if len(traj):  # the continuous drive, its times spread over the primitive
                t0 = tap.times[-1] if tap.times else 0.0
                tap.substeps.append(traj)
                tap.substep_times.append(np.linspace(t0, info["time_s"][i], len(traj) + 1)[1:])
            tap.states.append(int(obs[i]))
            tap.poses.append(tuple(info["pose"][i]))
            tap.times.append(float(info["time_s"][i]))
            records = base.contact_records(i)
            for c in records[tap.records_seen:]:
                tap.contacts.append((c.x_m, c.y_m))
                tap.contact_steps.append(len(tap.states) - 1)
            tap.records_seen = len(records)
        return obs, r, term, trunc, info

    def log_to(self, i: int, rec: Recorder, episode: int) -> None:
        """Log sub-env ``i``'s armed episode (nothing if it was not armed)."""
        tap = self.taps[i]
        if not tap.states:
            return
        rec.log_episode_trajectory(
            episode, np.asarray(tap.states), poses=np.asarray(tap.poses),
            contacts=np.asarray(tap.contacts).reshape(-1, 2),
            sim_time_s=np.asarray(tap.times), kind="train",
            contact_steps=np.asarray(tap.contact_steps, dtype=np.int64),
            substeps=(np.concatenate(tap.substeps) if tap.substeps else None),
            substep_times_s=(np.concatenate(tap.substep_times) if tap.substeps else None))


@dataclass
class _Tap:
    """One tapped sub-env's episode so far."""

    armed: bool = False
    records_seen: int = 0  # the sub-env's contact records already taken
    states: list[int] = field(default_factory=list)
    poses: list[tuple[float, float, float]] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    contacts: list[tuple[float, float]] = field(default_factory=list)
    contact_steps: list[int] = field(default_factory=list)
    substeps: list[np.ndarray] = field(default_factory=list)  # every step's pose, per primitive
    substep_times: list[np.ndarray] = field(default_factory=list)

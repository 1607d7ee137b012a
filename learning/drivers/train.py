"""Training on a tabular model with the fused kernels, and the metrics of a run.

:func:`train_tabular` runs the kernel in chunks of ``test_every`` episodes.
numba cannot read a clock, so each chunk is timed from Python and its time is
spread evenly over its episodes (``wall_time_s``); between chunks it runs a greedy
test from S. Tests draw no random numbers, so where they happen never changes
the training run, which is what lets a run resume from a checkpoint bit for bit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from learning.compiled.kernels import NO_TRACE, greedy_route, on_shortest_fraction, run_episodes
from learning.compiled.named_state import copy_state, episodes_done
from learning.config import MethodConfig
from learning.drivers.checkpoint import Checkpoint, CheckpointError
from learning.drivers.state import init_state
from learning.geometry import TabularMDP, geometry_of
from learning.metrics import (
    episodes_to_first_optimal,
    episodes_to_stable_optimal,
    optimal_test_fraction,
    reward_per_step,
)

EPISODE_FIELDS = ("steps", "success", "returns", "wall_time_s", "shaping_mean", "shaping_std")
KERNEL_OUT = ("steps", "returns", "success", "shaping_mean", "shaping_std")  # run_episodes' out
_DTYPES = {"steps": np.int32, "success": np.bool_}


def episode_arrays(n_episodes: int) -> dict[str, np.ndarray]:
    """A run's per-episode logs, zeroed (:data:`EPISODE_FIELDS`: steps int32, success bool,
    the rest float64), as every driver fills them."""
    return {f: np.zeros(n_episodes, dtype=_DTYPES.get(f, np.float64)) for f in EPISODE_FIELDS}




@dataclass(eq=False)
class TrainResult:
    """Everything a run measured; arrays are per episode unless named ``test_*``."""

    config: MethodConfig
    state: object  # the trained agent: its method's named state (tables, weights)
    episodes: int  # episodes trained in all
    env_steps: int  # env steps in all
    steps: np.ndarray  # int32[n]; steps of each episode
    success: np.ndarray  # bool[n]; reached the goal
    returns: np.ndarray  # float64[n]; sum of env rewards (no shaping)
    wall_time_s: np.ndarray  # float64[n]; seconds, chunk time / episodes in the chunk
    shaping_mean: np.ndarray  # float64[n]; mean shaping term F (0 without shaping)
    shaping_std: np.ndarray  # float64[n]
    test_episodes: np.ndarray  # int64[m]; episodes trained when each greedy test ran
    test_route_length: np.ndarray  # int64[m]; greedy route S->G in steps, -1 if G not reached
    optimal_length: int  # BFS moves S->G
    final_route: list[int]  # final greedy route from S (states, S first)
    final_route_length: int  # its length in steps, -1 if G not reached
    optimal_action_fraction: float  # reachable free cells whose greedy move is on a shortest route

    @property
    def reward_per_step(self) -> float:
        """Total return / total steps over the whole run (ratio of sums, see learning.metrics)."""
        return reward_per_step(self.returns, self.steps)

    @property
    def final_route_excess(self) -> int | None:
        """Final route length minus the optimum; None if G is not reached."""
        if self.final_route_length < 0:
            return None
        return self.final_route_length - self.optimal_length

    @property
    def episodes_to_optimal(self) -> int | None:
        """Episodes trained at the first greedy test whose route is a shortest one (first hit;
        a secondary figure: rank by :attr:`episodes_to_stable_optimal`)."""
        return episodes_to_first_optimal(self.test_episodes, self.test_route_length,
                                         self.optimal_length)

    @property
    def episodes_to_stable_optimal(self) -> int | None:
        """Episodes trained at the first greedy test from which every later test is optimal."""
        return episodes_to_stable_optimal(self.test_episodes, self.test_route_length,
                                          self.optimal_length)

    @property
    def optimal_test_fraction(self) -> float | None:
        """Share of optimal greedy tests over the last 10 % of tests."""
        return optimal_test_fraction(self.test_route_length, self.optimal_length)

    def episode_arrays(self) -> dict[str, np.ndarray]:
        return {f: getattr(self, f) for f in EPISODE_FIELDS}


def greedy_test(st, model: TabularMDP, start: int | None = None) -> tuple[int, list]:
    """(route length or -1, route states) of the exploitation policy from ``start`` (S)."""
    route = np.zeros(int(model.max_steps) + 1, dtype=np.int32)
    s0 = int(model.start if start is None else start)
    length, n = greedy_route(st, model.next_state, model.terminal, s0, int(model.max_steps), route)
    return int(length), route[:n].tolist()


def epsilon_route_lengths(st, model: TabularMDP, eps: float,
                          rng: np.random.Generator, n: int = 20) -> np.ndarray:
    """Route lengths (-1: G missed) of ``n`` epsilon-greedy rollouts from S, no learning."""
    from learning.compiled.kernels import epsilon_rollouts

    return epsilon_rollouts(st, model.next_state, model.terminal, int(model.start),
                            int(model.max_steps), float(eps), int(n), rng)


def shortest_fraction(st, model: TabularMDP) -> float:
    return float(on_shortest_fraction(st, model.next_state, model.distance_to_goal,
                                      model.start_states))


def _resume(ck: Checkpoint, cfg: MethodConfig, model: TabularMDP, n_episodes: int,
            rng: np.random.Generator, arrays: dict[str, np.ndarray],
            start_rng: np.random.Generator | None = None) -> tuple[object, int, int]:
    """Check ``ck`` fits this run, restore ``rng`` and the metrics so far; a copy of its state."""
    ck.check_compatible(cfg, model.next_state.shape[0], geometry_of(model))
    done = ck.episodes
    if done > n_episodes:
        raise CheckpointError(f"{ck.path}: field 'episodes' is {done}, more than the "
                              f"{n_episodes} episodes asked for; ask for more episodes")
    try:
        rng.bit_generator.state = ck.rng_state
    except (ValueError, TypeError, KeyError) as exc:
        raise CheckpointError(f"{ck.path}: field 'rng_state' does not fit this run's "
                              f"{type(rng.bit_generator).__name__} generator ({exc}); "
                              "resume with numpy.random.default_rng") from None
    if (start_rng is None) != (ck.start_rng_state is None):
        raise CheckpointError(f"{ck.path}: field 'start_rng_state' is "
                              f"{'missing' if ck.start_rng_state is None else 'present'} but "
                              f"this run {'has' if start_rng is not None else 'has no'} start "
                              "stream of its own; resume with the command that saved it")
    if start_rng is not None:
        start_rng.bit_generator.state = ck.start_rng_state
    for f in EPISODE_FIELDS:  # an agent's checkpoint has no metrics: those stay 0
        if f in ck.metrics:
            if ck.metrics[f].shape[0] < done:
                raise CheckpointError(f"{ck.path}: field 'metric_{f}' has "
                                      f"{ck.metrics[f].shape[0]} episodes, not {done}; the "
                                      "file is corrupt, delete it and train again")
            arrays[f][:done] = ck.metrics[f][:done]
    return copy_state(ck.state), done, ck.env_steps


class TrainObserver(Protocol):
    """Watches a run between kernel chunks (e.g. a recorder); never draws random numbers."""

    def trace_chunk(self, first_episode: int, n: int) -> bool:
        """Whether the states of episodes ``first_episode .. first_episode + n - 1`` are wanted."""

    def after_chunk(self, first_episode: int, n: int, trace: np.ndarray | None,
                    arrays: dict[str, np.ndarray], state,
                    test: tuple[int, list[int]]) -> None:
        """After a chunk: its traces (or None), the metric arrays so far, the greedy test."""


def train_tabular(cfg: MethodConfig, model: TabularMDP, n_episodes: int, rng: np.random.Generator,
                  test_every: int = 10, resume: Checkpoint | None = None,
                  observer: TrainObserver | None = None,
                  start_rng: np.random.Generator | None = None) -> TrainResult:
    """Train ``cfg`` on ``model`` for ``n_episodes`` episodes in all.

    ``rng`` is the learner's source of randomness (RN-QL's initial weights,
    exploration, ties, planning); episode starts come from ``start_rng`` when
    given (common random numbers: see :mod:`learning.streams`), else from ``rng``. ``resume`` (a
    :class:`learning.drivers.checkpoint.Checkpoint`) continues a run: its agent state,
    metrics and generator state are restored (``rng`` is set to the saved
    state), and training goes on from ``resume.episodes`` to ``n_episodes``,
    ending exactly where an uninterrupted run with the same seed would.
    ``observer`` sees each chunk (outside the timed region) and may ask for the
    chunk's state traces; it changes nothing about the run.
    """
    if test_every < 1:
        raise ValueError(f"test_every must be >= 1, got {test_every}")
    arrays = episode_arrays(n_episodes)
    tests_e: list[int] = []
    tests_l: list[int] = []
    if resume is None:
        st, done, env_steps = init_state(cfg, geometry_of(model), rng), 0, 0
    else:
        st, done, env_steps = _resume(resume, cfg, model, n_episodes, rng, arrays, start_rng)
        tests_e = [int(x) for x in resume.metrics.get("test_episodes", ())]
        tests_l = [int(x) for x in resume.metrics.get("test_route_length", ())]
    # compile (or load from the JIT cache) before the clock starts: 0 episodes draw nothing
    run_episodes(st, model, 0, rng, tuple(arrays[f][:0] for f in KERNEL_OUT))
    while done < n_episodes:
        n = min(test_every - done % test_every, n_episodes - done)
        out = tuple(arrays[f][done:done + n] for f in KERNEL_OUT)
        trace = NO_TRACE
        if observer is not None and observer.trace_chunk(done, n):
            trace = np.full((n, int(model.max_steps) + 1), -1, dtype=np.int32)
        t0 = time.perf_counter()
        env_steps += run_episodes(st, model, n, rng, out, trace, start_rng)
        arrays["wall_time_s"][done:done + n] = (time.perf_counter() - t0) / n
        done += n
        test = greedy_test(st, model)
        tests_e.append(done)
        tests_l.append(test[0])
        if observer is not None:
            observer.after_chunk(done - n, n, trace if trace.shape[0] else None, arrays, st,
                                 test)
    assert episodes_done(st) == done
    return finished(cfg, st, model, done, env_steps, arrays, tests_e, tests_l)


def finished(cfg: MethodConfig, st, model: TabularMDP, episodes: int, env_steps: int,
             arrays: dict[str, np.ndarray], tests_e: list[int], tests_l: list[int]
             ) -> TrainResult:
    """The :class:`TrainResult` of a finished run: its metrics, its tests, and the final
    greedy route and policy read from ``st`` (any learner's state, a graded policy's too)."""
    length, route = greedy_test(st, model)
    return TrainResult(config=cfg, state=st, episodes=episodes, env_steps=env_steps, **arrays,
                       test_episodes=np.asarray(tests_e, dtype=np.int64),
                       test_route_length=np.asarray(tests_l, dtype=np.int64),
                       optimal_length=int(model.distance_to_goal[model.start]), final_route=route,
                       final_route_length=length,
                       optimal_action_fraction=shortest_fraction(st, model))

"""A batched plain learner's grid runs in lock-step: every run of the batch steps at once.

:func:`train_plain_batch` is :func:`learning.drivers.plain_train.train_plain` for the runs
of a batched learner (:mod:`learning.plain.batched`): one ``act_batch`` and one
``update_batch`` call per step for every run still training, each run on its own streams
with its own starts, episodes, time limit and greedy tests from S, so run i equals
``train_plain`` of the learner's run i (tested against ``st-ql`` figure for figure). Runs
end their episodes at different steps; a run that has finished all its episodes sits out.
The batch's wall time is shared evenly over its runs' episodes (they train together).
"""

from __future__ import annotations

import time

import numpy as np

from learning.drivers.train import TrainResult, episode_arrays, finished
from learning.geometry import TabularMDP, geometry_of
from learning.plain.batched import OneRun, actions_of
from learning.plain.learner import (
    PlainAgent,
    PlainConfig,
    greedy_walk,
    learner_calls,
    snapshot,
)


def train_plain_batch(cfg: PlainConfig, model: TabularMDP, n_episodes: int,
                      rngs: list[np.random.Generator], test_every: int = 10,
                      start_rngs: list[np.random.Generator] | None = None
                      ) -> list[TrainResult]:
    """Train ``len(rngs)`` runs of the batched learner ``cfg.learner`` for ``n_episodes``
    episodes each; run i draws from ``rngs[i]`` and its starts from ``start_rngs[i]``
    (default ``rngs[i]``). One :class:`TrainResult` per run, in order."""
    if test_every < 1:
        raise ValueError(f"test_every must be >= 1, got {test_every}")
    geom = geometry_of(model)
    n_states, n_actions = int(geom.n_states), int(geom.n_actions)
    k = len(rngs)
    start_rngs = list(rngs) if start_rngs is None else list(start_rngs)
    next_state, reward, terminal = model.next_state, model.reward, model.terminal
    # flat tables: one gather per step for a (state, action) pair instead of a 2-D one
    next_flat, reward_flat = next_state.ravel(), reward.ravel()
    starts, max_steps, start = model.start_states, int(model.max_steps), int(model.start)
    batch = type(cfg).learner(n_states, n_actions, list(rngs))
    views = [OneRun(batch, i, n_actions) for i in range(k)]
    arrays = [episode_arrays(n_episodes) for _ in range(k)]
    tests: list[tuple[list[int], list[int]]] = [([], []) for _ in range(k)]
    s = np.array([starts[r.integers(0, starts.shape[0])] for r in start_rngs], np.int64)
    t = np.zeros(k, np.int64)
    ret = np.zeros(k)
    episode = np.zeros(k, np.int64)
    env_steps = np.zeros(k, np.int64)
    active = np.ones(k, bool)
    runs = np.arange(k, dtype=np.int64)  # the runs still training
    begin = getattr(batch, "episode_start_batch", None)
    act, update = batch.act_batch, batch.update_batch
    t0 = time.perf_counter()
    with learner_calls(views[0]):  # its failure is the runs', said in one line
        if begin is not None:
            begin(runs.copy())
        while n_episodes and runs.size:
            asked = runs.copy()  # the learner's to keep (a torch tensor may share it)
            sr = s[runs]
            a = actions_of(act(asked, sr), runs.size, n_actions)
            pair = sr * n_actions + a
            s2 = next_flat[pair]
            r = reward_flat[pair]
            done = terminal[s2]
            tr = t[runs] + 1
            t[runs] = tr
            update(asked, sr, a, r, s2, done)
            ret[runs] += r
            s[runs] = s2
            ended = done | (tr >= max_steps)
            if not ended.any():  # most steps: nobody's episode ends
                continue
            restart = []
            for i, d in zip(runs[ended].tolist(), done[ended].tolist(), strict=True):
                e = int(episode[i])
                arr = arrays[i]
                arr["steps"][e], arr["returns"][e], arr["success"][e] = t[i], ret[i], d
                env_steps[i] += t[i]
                episode[i] = e = e + 1
                if e % test_every == 0 or e == n_episodes:
                    length, _ = greedy_walk(views[i], next_state, terminal, start, max_steps)
                    tests[i][0].append(e)
                    tests[i][1].append(length)
                if e == n_episodes:
                    active[i] = False
                    continue
                s[i] = starts[start_rngs[i].integers(0, starts.shape[0])]
                t[i], ret[i] = 0, 0.0
                restart.append(i)
            if not active[runs].all():
                runs = np.flatnonzero(active)
            if restart and begin is not None:
                begin(np.array(restart, np.int64))
    wall = (time.perf_counter() - t0) / max(1, k * n_episodes)
    results = []
    for i in range(k):
        arrays[i]["wall_time_s"][:] = wall
        with learner_calls(views[i]):
            st = snapshot(views[i], cfg, n_states, n_actions)
        res = finished(cfg, st, model, n_episodes, int(env_steps[i]), arrays[i], *tests[i])
        res.agent = PlainAgent(cfg, views[i], st)  # type: ignore[attr-defined]
        results.append(res)
    return results


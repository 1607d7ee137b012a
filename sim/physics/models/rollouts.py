"""A policy driven from S many times in the physics world at a fidelity: what it achieves.

Above ``exact`` a primitive's outcome is random (wheel noise, a pose carried from the
last contact), so one drive of a policy is one sample: a policy that reaches G in 98 %
of drives can miss in the one drive that is shown, and one that misses a quarter of the
time can reach G in it. A policy is graded by driving it ``n`` times, each rollout a
robot of one :class:`sim.physics.envs.vector.PhysicsRouteVectorEnv` (one Space, one compiled
call per primitive for all of them) with its own noise stream, seeded from
``(seed, tag, k)`` so rollout ``k`` of every method sees the same stream (common random
numbers). P(G) carries a Wilson 95 % interval.

At ``exact`` every rollout is the same, so ``n = 1`` is the deterministic test.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from gymnasium.vector import AutoresetMode

from sim.physics.envs.vector import PhysicsRouteVectorEnv
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.rollout import drive_batch
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

Z95 = 1.959963984540054  # two-sided 95 % normal quantile


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a binomial proportion (good at 0/n and n/n, where the
    normal approximation collapses to a point)."""
    if n <= 0:
        return 0.0, 1.0
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass(frozen=True)
class Rollouts:
    """``n`` drives of one policy from S; arrays per rollout."""

    reached: np.ndarray  # bool[n]: entered G within the step budget
    primitives: np.ndarray  # int64[n]: primitives driven (the budget when G was missed)
    contacts: np.ndarray  # int64[n]: contacts that began
    bumps: np.ndarray  # int64[n]: primitives that ended in a bump
    sim_time_s: np.ndarray  # float64[n]: simulated time [s]
    metres: np.ndarray  # float64[n]: path length driven [m] (nan when not measured)
    routes: list[list[int]]  # the cells of each rollout, S first (empty when not kept)
    path: np.ndarray  # float64[m, 3]: rollout 0's poses, as the env's info trajectories
    #                   concatenate (each primitive's start pose, then every physics step)
    poses: np.ndarray  # float64[k + 1, 3]: rollout 0's pose at S and after each primitive

    @property
    def n(self) -> int:
        return int(self.reached.size)

    @property
    def p_goal(self) -> float:
        return float(self.reached.mean()) if self.n else 0.0

    @property
    def p_goal_interval(self) -> tuple[float, float]:
        return wilson_interval(int(self.reached.sum()), self.n)

    def median_primitives(self) -> float:
        """Median primitives to G, a rollout that missed counting as infinite."""
        v = np.where(self.reached, self.primitives.astype(float), np.inf)
        return float(np.median(v)) if self.n else math.inf

    def summary(self) -> dict[str, object]:
        """The record's fields (means over rollouts; primitives over those that reached G)."""
        lo, hi = self.p_goal_interval
        hit = self.reached
        med = self.median_primitives()
        return {
            "rollouts": self.n,
            "p_goal": round(self.p_goal, 6),
            "p_goal_ci95": [round(lo, 6), round(hi, 6)],
            "primitives_mean": (round(float(self.primitives[hit].mean()), 4)
                                if hit.any() else None),
            "primitives_median": None if not math.isfinite(med) else med,
            "contacts_mean": round(float(self.contacts.mean()), 4),
            "bumps_mean": round(float(self.bumps.mean()), 4),
            "metres_mean": (None if np.isnan(self.metres).all()
                            else round(float(np.nanmean(self.metres)), 4)),
            "sim_time_s_mean": round(float(self.sim_time_s.mean()), 4),
        }


def rollout_env(sc: Scenario, n: int, fidelity: Fidelity, config: PhysicsConfig | None = None,
                *, trajectories: bool = False) -> PhysicsRouteVectorEnv:
    """A vector env of ``n`` robots for :func:`drive_policy` to reuse."""
    return PhysicsRouteVectorEnv(n, sc, config=config, fidelity=fidelity,
                                 autoreset_mode=AutoresetMode.DISABLED,
                                 trajectories=trajectories, contact_records=False)


def rollout_rngs(seed: int, tag: int, n: int) -> list[np.random.Generator]:
    """Rollout ``k``'s noise stream: the same for every method of a seed (``tag`` names
    the test, e.g. the episode it ran after)."""
    return [np.random.default_rng([int(seed), int(tag), k, 0x524F4C4C]) for k in range(n)]


def drive_policy(sc: Scenario, policy: np.ndarray | Callable[[np.ndarray], np.ndarray],
                 fidelity: Fidelity, n: int, seed: int = 0, tag: int = 0,
                 max_steps: int | None = None, config: PhysicsConfig | None = None, *,
                 measure_metres: bool = False, keep_routes: bool = False,
                 keep_path: bool = False, env: PhysicsRouteVectorEnv | None = None
                 ) -> Rollouts:
    """Drive ``policy`` (``int[nS]``, an action per cell, or ``f(states) -> actions``) from S
    ``n`` times at ``fidelity``, each rollout for at most ``max_steps`` primitives (default:
    the scenario's episode length). ``env``: a :func:`rollout_env` of ``n`` sub-envs to
    reuse (its Space and static shapes are built once; every rollout is reset anyway)."""
    n = int(n)
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    if env is None:
        env = rollout_env(sc, n, fidelity, config, trajectories=measure_metres or keep_path)
    elif env.num_envs != n or ((measure_metres or keep_path)
                               and not env.batch.records_trajectories):
        raise ValueError("the env to reuse must have n sub-envs (and trajectories if "
                         "metres or the path are wanted)")
    tables = None
    if callable(policy):
        act = policy
    else:
        table = np.asarray(policy, dtype=np.int64)
        tables = (table[None], np.zeros(n, np.int64))

        def act(s: np.ndarray) -> np.ndarray:
            return table[s]
    r, path, poses = _drive(env, act, rollout_rngs(seed, tag, n),
                            int(max_steps or sc.steps_per_episode), measure_metres, keep_routes,
                            [0] if keep_path else [], tables)
    empty = np.zeros((0, 3))
    return replace(r, path=path.get(0, empty), poses=poses.get(0, empty))


def drive_epsilon_greedy(sc: Scenario, table: np.ndarray, eps: float,
                         rng: np.random.Generator, fidelity: Fidelity, n: int, seed: int = 0,
                         tag: int = 0, max_steps: int | None = None) -> Rollouts:
    """:func:`drive_policy` of the epsilon-greedy policy of ``table`` (``int[nS]``), every
    drive in compiled code: each round of primitives draws ``rng.random(n) < eps`` and then
    ``rng.integers(0, 4, n)`` for all ``n`` rollouts (finished ones too), a drawn action
    replacing the table's where the first says so, exactly as :func:`drive_policy` with
    ``f(s) = where(rng.random(n) < eps, rng.integers(0, 4, n), table[s])`` draws them; and
    ``rng`` is left where that drive leaves it (the rounds' draws are made ahead for the
    most rounds a drive can take, then the generator is rewound and advanced by the rounds
    the longest drive took)."""
    n, limit = int(n), int(max_steps or sc.steps_per_episode)
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    start = rng.bit_generator.state
    override = np.full((limit, n), -1, np.int64)
    for j in range(limit):
        explore = rng.random(n) < eps
        drawn = rng.integers(0, 4, n)
        override[j, explore] = drawn[explore]
    table = np.asarray(table, dtype=np.int64)
    r, _, _ = _drive(rollout_env(sc, n, fidelity), lambda s: table[s],
                     rollout_rngs(seed, tag, n), limit, False, False, [],
                     (table[None], np.zeros(n, np.int64)), override=override)
    rng.bit_generator.state = start
    for _ in range(int(r.primitives.max())):  # the rounds the drive took
        rng.random(n)
        rng.integers(0, 4, n)
    return r


def drive_policies(sc: Scenario, tables: list[np.ndarray], fidelity: Fidelity, n: int,
                   seeds: list[int], tags: list[int], max_steps: int | None = None, *,
                   measure_metres: bool = False, keep_routes: bool = False,
                   keep_path: bool = False, env: PhysicsRouteVectorEnv | None = None,
                   median_only: bool = False) -> list[Rollouts]:
    """:func:`drive_policy` of several policies (``tables[j]``, ``int[nS]``) at once, in one
    env of ``len(tables) x n`` robots: policy j's rollouts are robots ``j*n ..``, each with
    the noise stream :func:`drive_policy` would give it (``seeds[j]``, ``tags[j]``), so each
    policy's Rollouts equal its own drive's (robots in one Space do not meet; ``keep_path``:
    each policy's rollout 0). The periodic greedy tests and the final gradings of many runs
    share one compiled call per primitive this way, instead of one per run. ``median_only``
    (a periodic test): only each policy's :meth:`Rollouts.median_primitives` and its rollout
    0 are wanted, and a drive that cannot change the median is cut short and counted as a
    miss (:func:`sim.physics.kernel.rollout.drive_batch`): the median and rollout 0 are the
    whole drives' own, the other rollouts' figures are not."""
    m, n = len(tables), int(n)
    if m < 1 or n < 1:
        raise ValueError(f"need at least one policy and n >= 1, got {m} and {n}")
    if env is None:
        env = rollout_env(sc, m * n, fidelity, trajectories=measure_metres or keep_path)
    elif env.num_envs != m * n or ((measure_metres or keep_path)
                                   and not env.batch.records_trajectories):
        raise ValueError("the env to reuse must have len(tables) x n sub-envs (and "
                         "trajectories if metres or the path are wanted)")
    stacked = np.stack([np.asarray(t, dtype=np.int64) for t in tables])
    owner = np.repeat(np.arange(m), n)

    def act(s: np.ndarray) -> np.ndarray:
        return stacked[owner, s]
    rngs = [r for j in range(m) for r in rollout_rngs(seeds[j], tags[j], n)]
    shown = [j * n for j in range(m)] if keep_path else []
    r, paths, poses = _drive(env, act, rngs, int(max_steps or sc.steps_per_episode),
                             measure_metres, keep_routes, shown, (stacked, owner),
                             n if median_only else 0)
    empty = np.zeros((0, 3))
    return [Rollouts(r.reached[j * n:(j + 1) * n], r.primitives[j * n:(j + 1) * n],
                     r.contacts[j * n:(j + 1) * n], r.bumps[j * n:(j + 1) * n],
                     r.sim_time_s[j * n:(j + 1) * n], r.metres[j * n:(j + 1) * n],
                     r.routes[j * n:(j + 1) * n], paths.get(j * n, empty),
                     poses.get(j * n, empty)) for j in range(m)]


def _drive_tables(env: PhysicsRouteVectorEnv, tables: tuple[np.ndarray, np.ndarray],
                  s: np.ndarray, info: dict, limit: int, measure_metres: bool,
                  keep_routes: bool, shown: list[int], median_of: int,
                  override: np.ndarray | None
                  ) -> tuple[Rollouts, dict[int, np.ndarray], dict[int, np.ndarray]]:
    """:func:`_drive` of table policies, every drive in compiled code."""
    n = env.num_envs
    tallies, visited, metres, paths, poses = drive_batch(
        env.batch, tables[0], tables[1], s.copy(), env.model.goal, limit, keep_routes,
        measure_metres, shown, median_of, override)
    env.park(np.ones(n, bool))  # driven behind the env's back: they sit out until reset
    prims = tallies[0]
    routes = [visited[i, :prims[i] + 1].tolist() for i in range(n)] if keep_routes else []
    empty = np.zeros((0, 3))
    r = Rollouts(tallies[3] > 0, prims, tallies[1], tallies[2], tallies[4] * env.config.dt_s,
                 metres if measure_metres else np.full(n, np.nan), routes, empty, empty)
    return (r, {k: np.concatenate([info["pose"][k:k + 1], p]) for k, p in zip(shown, paths,
                                                                               strict=True)},
            {k: np.concatenate([info["pose"][k][None], q]) for k, q in zip(shown, poses,
                                                                            strict=True)})


def _drive(env: PhysicsRouteVectorEnv, act: Callable[[np.ndarray], np.ndarray],
           rngs: list[np.random.Generator], limit: int, measure_metres: bool,
           keep_routes: bool, shown: list[int],
           tables: tuple[np.ndarray, np.ndarray] | None = None, median_of: int = 0,
           override: np.ndarray | None = None
           ) -> tuple[Rollouts, dict[int, np.ndarray], dict[int, np.ndarray]]:
    """Every sub-env of ``env`` driven from S with its noise stream ``rngs[k]``, actions
    ``act(states)``, for at most ``limit`` primitives; with the path and the poses after
    each primitive of the robots ``shown`` (the Rollouts' own ``path`` and ``poses`` are
    left empty). ``tables``: (policies ``int[m, nS]``, each robot's policy ``int[N]``), the
    same actions as ``act``: then every drive runs whole in compiled code
    (:mod:`sim.physics.kernel.rollout`; the same drives, paths and poses included; with
    ``median_of`` = n, drives that cannot change their policy's median cut short; with
    ``override`` (int64[limit, N]), where >= 0, the actions that replace the tables')."""
    n = env.num_envs
    env.max_episode_steps = limit
    for k, rng in enumerate(rngs):
        env.set_noise_rng(k, rng)
    s, info = env.reset(options={"start": "S"})
    if tables is not None:
        return _drive_tables(env, tables, s, info, limit, measure_metres, keep_routes, shown,
                             median_of, override)
    path = {k: [info["pose"][k:k + 1].copy()] for k in shown}
    poses = {k: [info["pose"][k].copy()] for k in shown}
    running = np.ones(n, bool)
    reached = np.zeros(n, bool)
    prims = np.zeros(n, np.int64)
    contacts = np.zeros(n, np.int64)
    bumps = np.zeros(n, np.int64)
    sim_t = np.zeros(n)
    metres = np.zeros(n) if measure_metres else np.full(n, np.nan)
    states = [s.copy()]  # every robot's cell after each primitive (routes)
    while running.any():
        a = np.asarray(act(s), dtype=np.int64)
        s2, _, term, trunc, info = env.step(np.where(running, a, 0))
        prims += running
        contacts += info["contacts"]
        bumps += info["bumped"]
        if measure_metres:
            metres += np.where(running, env.primitive_metres(), 0.0)
        for k in shown:
            if running[k]:
                path[k].append(env.trajectory(k))
                poses[k].append(info["pose"][k].copy())
        if keep_routes:
            states.append(s2.copy())
        reached |= term
        ended = term | trunc
        sim_t = np.where(ended, info["time_s"], sim_t)
        running &= ~ended
        s = s2
    routes: list[list[int]] = []
    if keep_routes:
        visited = np.stack(states)
        routes = [visited[:prims[i] + 1, i].tolist() for i in range(n)]
    empty = np.zeros((0, 3))
    return (Rollouts(reached, prims, contacts, bumps, sim_t, metres, routes, empty, empty),
            {k: np.concatenate(v) for k, v in path.items()},
            {k: np.asarray(v) for k, v in poses.items()})

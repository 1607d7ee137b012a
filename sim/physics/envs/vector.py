"""``rnhql/PhysicsRoute-v0`` and ``rnhql/DiffDrive-v0`` as gymnasium vector envs: N robots in
one Pymunk Space.

``gymnasium.make_vec("rnhql/PhysicsRoute-v0", num_envs=N,
vectorization_mode="vector_entry_point")`` returns a :class:`PhysicsRouteVectorEnv`:
one :class:`sim.physics.kernel.batch.RouteBatch` whose robot ``i`` is sub-env ``i``. A batched
step is one compiled call for all robots (Chipmunk only for guards and contact steps),
where a ``SyncVectorEnv`` would step N Python envs in turn.

Sub-env ``i`` reset with seed ``seed + i`` (or ``seed[i]``) is the single env reset with
that seed: same observations, rewards, terminations, truncations and ``info`` for the
same actions, and the same as gymnasium's own ``SyncVectorEnv`` over the single envs in
every autoreset mode (tested). ``info`` has the single env's keys, stacked over sub-envs
with gymnasium's ``_key`` masks. Autoreset follows ``metadata["autoreset_mode"]``
(``autoreset_mode=`` at construction), each of gymnasium's three:

- ``NEXT_STEP`` (gymnasium's default): the step after a sub-env's episode ended resets it
  (its action is ignored, reward 0, not terminated or truncated, its ``info`` the reset's);
- ``SAME_STEP``: the step that ends an episode resets the sub-env at once; the returned
  observation and ``info`` are the new episode's, the ended episode's last observation
  and ``info`` are ``info["final_obs"]`` and ``info["final_info"]`` (masks
  ``_final_obs``, ``_final_info``), as Stable-Baselines3 wants (:mod:`sim.sb3_vec`);
- ``DISABLED``: the caller resets ended sub-envs (``reset(options={"reset_mask": m})``);
  until then an ended sub-env sits out every step (observation unchanged, reward 0,
  neither terminated nor truncated, its ``_key`` masks False).

Autoresets use ``autoreset_options`` (default: start at S, as a bare ``reset()`` of the
single env).

``DiffDrive-v0``'s vector form (:class:`DiffDriveVectorEnv`) keeps N single envs whose
worlds share one :class:`sim.physics.reference.world.SharedSpace`: each control period, every robot
sets its wheels and clamps its step, then the one Space steps all of them at once
(contacts are routed to the robot whose shape began them). Robots never touch each
other and each robot's own constraints are solved in the same order as alone, so
sub-env ``i`` equals the single env with its seed (tested, poses within 1e-9 m).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from sim.env_args import (
    SCENARIO_REWARDS,
    config_arg,
    discrete_actions,
    env_scenario,
    episode_limit,
    real_actions,
)
from sim.grid.env import start_state_from_options, starts_option
from sim.physics.envs.diffdrive import DIFFDRIVE_CONFIG, DiffDriveEnv, diffdrive_periods
from sim.physics.envs.route import PhysicsRouteEnv
from sim.physics.envs.vector_args import (
    reset_mask_option,
    sub_env_seeds,
    vector_setup,
)
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.physics.reference.world import SharedSpace
from sim.physics.static import PhysicsConfig
from sim.scenario import Rewards, Scenario

INFO_KEYS = ("state", "bumped", "reached", "timeout", "steps", "contacts", "pose", "time_s")
MASK_KEYS = tuple(f"_{k}" for k in INFO_KEYS)


def stack_infos(per_env: list[dict[str, Any] | None], n: int) -> dict[str, Any]:
    """Single-env ``info`` dicts stacked as gymnasium's vector envs do: ``key`` an array over
    sub-envs (zeros where a sub-env has none), ``_key`` the mask of those that have it."""
    out: dict[str, Any] = {}
    for i, info in enumerate(per_env):
        if info is None:
            continue
        for k, v in info.items():
            if k not in out:
                a = np.asarray(v)
                out[k] = np.zeros((n, *a.shape), dtype=a.dtype)
                out[f"_{k}"] = np.zeros(n, bool)
            out[k][i] = v
            out[f"_{k}"][i] = True
    return out


def final_infos(infos: dict[str, Any], obs: np.ndarray, ended: np.ndarray
                ) -> dict[str, Any]:
    """``SAME_STEP``'s ``final_obs`` / ``final_info`` entries for the ended sub-envs (as
    gymnasium's ``SyncVectorEnv`` builds them): copies, masked to ``ended``."""
    final_obs = np.full(len(ended), None, dtype=object)
    for i in np.flatnonzero(ended):
        final_obs[i] = obs[i].copy() if obs.ndim > 1 else obs[i]
    final_info: dict[str, Any] = {}
    for k, v in infos.items():
        if k.startswith("_"):
            final_info[k] = v & ended
        else:
            final_info[k] = np.zeros_like(v)
            final_info[k][ended] = v[ended]
    return {"final_obs": final_obs, "_final_obs": ended.copy(),
            "final_info": final_info, "_final_info": ended.copy()}


class PhysicsRouteVectorEnv(VectorEnv):
    """N independent copies of ``PhysicsRoute-v0`` sharing one ``pymunk.Space``.

    Observations are ``int64[N]`` cells, actions ``int[N]`` in 0..3 (up, down, left,
    right). ``infos`` hold the single env's keys as arrays over sub-envs (gymnasium's
    ``key`` / ``_key`` form): ``state``, ``bumped``, ``reached``, ``timeout``, ``steps``
    (physics steps of the primitive), ``contacts`` (how many began), ``pose`` (N, 3)
    [m, m, rad] and ``time_s`` [s].

    The route problem's episode rules live here and nowhere else: the reward
    (:meth:`sim.scenario.Rewards.of_moves`), termination on entering G, truncation after
    ``max_episode_steps`` primitives, and each sub-env's own noise stream. Physics training
    (:mod:`scenarios.runs.physics`) steps this env; a single run is ``num_envs=1``.

    ``autoreset_mode``: ``NEXT_STEP`` (gymnasium's default), ``SAME_STEP`` or ``DISABLED``
    (see the module doc; a training loop whose runs finish at different times uses
    ``DISABLED`` and leaves finished runs sitting out). ``reset`` options: ``start``
    (``"S"``, ``"random"`` or a state, for every reset sub-env), ``starts`` (``int[N]``, a
    start state per sub-env; only masked entries are read), ``reset_mask`` (``bool[N]``).
    ``trajectories=True`` keeps every physics step's pose of the last primitive
    (:meth:`trajectory`) for recordings; ``contact_records=False`` keeps no contact records
    (:meth:`contact_records` stays empty; ``info["contacts"]`` still counts them);
    ``lean_infos=True`` gives only ``info["contacts"]`` and ``info["time_s"]`` (what the
    training loop reads: the full dict cost a plain learner's physics runs an eighth of
    their time). ``rewards``, ``fidelity``: as the single env (``make_vec`` passes the id's
    ``goal-only``; built directly, the scenario's scheme).
    ``max_episode_steps`` (or ``steps_per_episode``): default the scenario's. ``start``:
    where a reset without a ``start`` option (an autoreset too) begins, as the single env.

    ``gymnasium.make_vec("rnhql/PhysicsRoute-v0", 8, vectorization_mode="vector_entry_point",
    scenario="rooms-102", autoreset_mode="SameStep")``
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}  # noqa: RUF012

    def __init__(self, num_envs: int = 1, scenario: str | Scenario = "paper-50",
                 config: PhysicsConfig | None = None, max_episode_steps: int | None = None,
                 autoreset_options: dict[str, Any] | None = None,
                 render_mode: str | None = None,
                 fidelity: Fidelity | str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 trajectories: bool = False, rewards: str | Rewards = SCENARIO_REWARDS,
                 steps_per_episode: int | None = None, start: str | int = "S",
                 contact_records: bool = True, lean_infos: bool = False) -> None:
        num_envs = vector_setup(self, num_envs, render_mode, autoreset_mode)
        self.lean_infos = bool(lean_infos)
        # the single env's arguments, resolved as it resolves them (it builds no world
        # until reset): sub-env i is PhysicsRouteEnv with the same kwargs
        proto = PhysicsRouteEnv(scenario, config=config, fidelity=fidelity, rewards=rewards,
                                steps_per_episode=steps_per_episode, start=start)
        self.start = proto.start
        self.scenario = proto.scenario
        self.model = proto.model
        self.config = proto.config
        self.fidelity = proto.fidelity
        self.max_episode_steps = episode_limit(max_episode_steps, proto.steps_per_episode,
                                               "max_episode_steps")
        self.autoreset_options = autoreset_options
        self.batch = RouteBatch(self.scenario, num_envs, self.config, fidelity=self.fidelity,
                                trajectories=trajectories, contact_records=contact_records)
        self.single_observation_space = spaces.Discrete(self.model.n_states)
        self.single_action_space = spaces.Discrete(4)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._rewards = self.scenario.rewards
        self._goal = self.model.goal
        self._obs = np.zeros(num_envs, dtype=np.int64)
        self._elapsed = np.zeros(num_envs, dtype=np.int64)
        self._needs_reset = np.ones(num_envs, dtype=bool)
        self._rngs: list[np.random.Generator] = [seeding.np_random()[0]
                                                 for _ in range(num_envs)]
        self._own_noise = np.zeros(num_envs, dtype=bool)  # noise set by set_noise_rng

    @property
    def autoreset_mode(self) -> AutoresetMode:
        return self.metadata["autoreset_mode"]

    @property
    def rewards(self) -> Rewards:
        """The reward scheme every sub-env pays."""
        return self._rewards

    def set_noise_rng(self, i: int, rng: np.random.Generator) -> None:
        """Sub-env ``i`` draws its wheel noise from ``rng`` from now on, whatever seeds later
        resets get (a sweep gives each run its own physics stream)."""
        self.batch.set_noise_rng(int(i), rng)
        self._own_noise[i] = True

    def _reset_one(self, i: int, options: dict[str, Any] | None,
                   starts: np.ndarray | None = None) -> None:
        if starts is not None:  # checked by starts_option
            s = int(starts[i])
        else:
            s = start_state_from_options(options, self.model, self._rngs[i], self.start)
        x, y = self.batch.disc.state_centre(s)
        self.batch.place(i, x, y, 0.0)
        self._obs[i] = s
        self._elapsed[i] = 0
        self._needs_reset[i] = False

    def reset(self, *, seed: int | list[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every sub-env (or those in ``options["reset_mask"]``)."""
        seeds = sub_env_seeds(seed, self.num_envs)
        opts = dict(options or {})
        mask = reset_mask_option(opts, self.num_envs)
        starts = opts.pop("starts", None)
        if starts is not None:
            starts = starts_option(starts, mask, self.model)
        for i in np.flatnonzero(mask):
            if seeds[i] is not None:
                self._rngs[i] = seeding.np_random(seeds[i])[0]
            if not self._own_noise[i] and (seeds[i] is not None
                                           or self.batch._noise_rngs[i] is None):
                self.batch.set_noise_rng(int(i), self._rngs[i])  # as the single env does
            self._reset_one(int(i), opts or None, starts)
        return self._obs.copy(), self._infos(mask, None, mask)

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        acts = discrete_actions(actions, 4, self.num_envs)
        mode = self.autoreset_mode
        if mode == AutoresetMode.NEXT_STEP:
            resetting = self._needs_reset.copy()
            for i in np.flatnonzero(resetting):
                self._reset_one(int(i), self.autoreset_options)
            moving = ~resetting
        else:
            resetting = np.zeros(self.num_envs, bool)
            moving = ~self._needs_reset
        out = self.batch.step(acts, moving)
        obs = np.where(moving, out.state, self._obs)
        terminated = moving & (out.cell == self._goal)  # the true cell: where the robot is
        rewards = self._rewards.of_moves(out.bumped, terminated) * moving
        self._elapsed += moving
        truncated = moving & (self._elapsed >= self.max_episode_steps)
        self._obs[:] = obs
        ended = terminated | truncated
        if mode == AutoresetMode.DISABLED:
            self._needs_reset |= ended  # idle until the caller resets
            infos = self._infos(moving, out, resetting)
        elif mode == AutoresetMode.NEXT_STEP:
            self._needs_reset = ended
            infos = self._infos(np.ones(self.num_envs, bool), out, resetting)
        else:  # SAME_STEP: the ended episodes' last step goes to final_obs / final_info
            infos = self._infos(np.ones(self.num_envs, bool), out, resetting)
            if ended.any():
                final = final_infos(infos, obs, ended)
                for i in np.flatnonzero(ended):
                    self._reset_one(int(i), self.autoreset_options)
                infos = self._infos(np.ones(self.num_envs, bool), out, ended)
                infos.update(final)
        return self._obs.copy(), rewards.astype(np.float64), terminated, truncated, infos

    def park(self, mask: np.ndarray) -> None:
        """Sub-envs in ``mask`` sit out every step until reset (their robots driven elsewhere)."""
        self._needs_reset |= np.asarray(mask, dtype=bool)

    def trajectory(self, i: int) -> np.ndarray:
        """float64[n, 3]: sub-env ``i``'s pose before its last primitive, then after each
        physics step of it (needs ``trajectories=True``)."""
        return self.batch.trajectory(int(i))

    def primitive_metres(self) -> np.ndarray:
        """float64[num_envs]: each sub-env's path length over its last primitive [m] (needs
        ``trajectories=True``)."""
        return self.batch.primitive_metres()

    def contact_records(self, i: int) -> list[Any]:
        """Sub-env ``i``'s contacts (:class:`sim.physics.Contact`) since its last reset."""
        return self.batch.contacts[int(i)]

    def _infos(self, mask: np.ndarray, out: Any, fresh: np.ndarray) -> dict[str, Any]:
        """The single env's keys over sub-envs; ``fresh`` sub-envs were just reset (their
        entries are a reset's: not bumped, reached, no steps, no contacts)."""
        b, n = self.batch, self.num_envs
        r = b.r
        if self.lean_infos:  # the training loop's reads only
            contacts = (np.zeros(n, np.int64) if out is None else
                        np.where(fresh, 0, out.contacts).astype(np.int64))
            return {"contacts": contacts, "time_s": r.steps * self.config.dt_s}
        pose = np.empty((n, 3))
        pose[:, 0], pose[:, 1] = r.x, r.y
        np.add(r.th, np.pi, out=pose[:, 2])  # as wrap_angle
        np.remainder(pose[:, 2], 2.0 * np.pi, out=pose[:, 2])
        pose[:, 2] -= np.pi
        if out is None:
            bumped, timeout = np.zeros(n, bool), np.zeros(n, bool)
            reached, steps, contacts = np.ones(n, bool), np.zeros(n, np.int64), \
                np.zeros(n, np.int64)
        else:
            keep = ~fresh
            bumped, timeout = out.bumped & keep, out.timeout & keep
            reached = np.where(keep, out.reached, True)
            steps = np.where(keep, out.steps, 0).astype(np.int64)
            contacts = np.where(keep, out.contacts, 0).astype(np.int64)
        masks = np.repeat(mask[None], len(INFO_KEYS), axis=0)  # one array each, one alloc
        return {**dict(zip(INFO_KEYS, (self._obs.copy(), bumped, reached, timeout, steps,
                                       contacts, pose, r.steps * self.config.dt_s),
                           strict=True)),
                **dict(zip(MASK_KEYS, masks, strict=True))}


class DiffDriveVectorEnv(VectorEnv):
    """N copies of ``DiffDrive-v0`` (wheel speeds in, pose out) stepping in one Space.

    Observations ``float32[N, 8]``, actions ``float[N, 2]`` (left, right wheel speed
    [m/s]; clipped to the wheel limit as the single env does); ``infos`` hold the single
    env's keys (``state``, ``bumped``, ``in_contact``, ``contacts``, ``pose``, ``time_s``,
    ``wheels``) with gymnasium's ``_key`` masks. ``autoreset_mode``, ``rewards``,
    ``fidelity``, ``max_episode_steps`` / ``steps_per_episode`` as
    :class:`PhysicsRouteVectorEnv` (the episode length in control periods, default as the
    single env's).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}  # noqa: RUF012

    def __init__(self, num_envs: int = 1, scenario: str | Scenario = "paper-50",
                 config: PhysicsConfig | None = None, max_episode_steps: int | None = None,
                 autoreset_options: dict[str, Any] | None = None,
                 render_mode: str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 fidelity: Fidelity | str | None = None,
                 rewards: str | Rewards = SCENARIO_REWARDS,
                 steps_per_episode: int | None = None, start: str | int = "S") -> None:
        num_envs = vector_setup(self, num_envs, render_mode, autoreset_mode)
        sc = env_scenario(scenario, rewards)
        self.config = config_arg(config, DIFFDRIVE_CONFIG)
        self.shared = SharedSpace(sc, self.config)
        self.envs = [DiffDriveEnv(sc, config=self.config, shared=self.shared,
                                  fidelity=fidelity, start=start) for _ in range(num_envs)]
        self.start = self.envs[0].start
        self.scenario = sc
        self.fidelity = self.envs[0].fidelity
        default = episode_limit(steps_per_episode, diffdrive_periods(sc, self.config))
        self.max_episode_steps = episode_limit(max_episode_steps, default, "max_episode_steps")
        self.autoreset_options = autoreset_options
        self.single_observation_space = self.envs[0].observation_space
        self.single_action_space = self.envs[0].action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._obs = np.zeros((num_envs, 8), dtype=np.float32)
        self._elapsed = np.zeros(num_envs, dtype=np.int64)
        self._needs_reset = np.ones(num_envs, dtype=bool)

    @property
    def autoreset_mode(self) -> AutoresetMode:
        return self.metadata["autoreset_mode"]

    @property
    def rewards(self) -> Rewards:
        """The reward scheme every sub-env pays."""
        return self.scenario.rewards

    def _reset_one(self, i: int, seed: int | None, options: dict[str, Any] | None
                   ) -> dict[str, Any]:
        self._obs[i], info = self.envs[i].reset(seed=seed, options=options)
        self._elapsed[i] = 0
        self._needs_reset[i] = False
        return info

    def reset(self, *, seed: int | list[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        seeds = sub_env_seeds(seed, self.num_envs)
        opts = dict(options or {})
        mask = reset_mask_option(opts, self.num_envs)
        infos: list[Any] = [None] * self.num_envs
        for i in np.flatnonzero(mask):
            infos[i] = self._reset_one(int(i), seeds[i], opts or None)
        return self._obs.copy(), stack_infos(infos, self.num_envs)

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        acts = real_actions(actions, (self.num_envs, 2), "actions")
        mode = self.autoreset_mode
        infos: list[Any] = [None] * self.num_envs
        if mode == AutoresetMode.NEXT_STEP:
            resetting = self._needs_reset.copy()
            for i in np.flatnonzero(resetting):
                infos[i] = self._reset_one(int(i), None, self.autoreset_options)
            moving_mask = ~resetting
        else:
            moving_mask = ~self._needs_reset
        idx = np.flatnonzero(moving_mask)
        for i in idx:
            self.envs[i].begin_period(acts[i])
        moving = [self.envs[i] for i in idx]
        dt = self.config.dt_s
        for _ in range(self.config.substeps):
            for env in moving:
                env.command_substep()
            self.shared.step(dt)
            for env in moving:
                assert env.world is not None
                env.world.after_step(env._period_traj)
        rewards = np.zeros(self.num_envs)
        terminated = np.zeros(self.num_envs, bool)
        for i in idx:
            self._obs[i], rewards[i], terminated[i], _, infos[i] = self.envs[i].end_period()
        self._elapsed += moving_mask
        truncated = moving_mask & (self._elapsed >= self.max_episode_steps)
        ended = terminated | truncated
        if mode == AutoresetMode.DISABLED:
            self._needs_reset |= ended
            out = stack_infos(infos, self.num_envs)
        elif mode == AutoresetMode.NEXT_STEP:
            self._needs_reset = ended
            out = stack_infos(infos, self.num_envs)
        else:
            out = stack_infos(infos, self.num_envs)
            if ended.any():
                final = final_infos(out, self._obs, ended)
                for i in np.flatnonzero(ended):
                    infos[i] = self._reset_one(int(i), None, self.autoreset_options)
                out = stack_infos(infos, self.num_envs)
                out.update(final)
        return self._obs.copy(), rewards, terminated, truncated, out

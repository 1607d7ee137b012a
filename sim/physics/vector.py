"""``rnhql/PhysicsRoute-v0`` and ``rnhql/DiffDrive-v0`` as gymnasium vector envs: N robots in
one Pymunk Space.

``gymnasium.make_vec("rnhql/PhysicsRoute-v0", num_envs=N,
vectorization_mode="vector_entry_point")`` returns a :class:`PhysicsRouteVectorEnv`:
one :class:`sim.physics.batch.RouteBatch` whose robot ``i`` is sub-env ``i``. A batched
step is one compiled call for all robots (Chipmunk only for guards and contact steps),
where a ``SyncVectorEnv`` would step N Python envs in turn.

Sub-env ``i`` reset with seed ``seed + i`` (or ``seed[i]``) is the single env reset with
that seed: same observations, rewards, terminations, truncations and ``info`` figures
for the same actions (tested). Autoreset follows ``metadata["autoreset_mode"]``
(``NEXT_STEP``, gymnasium's default): the step after a sub-env's episode ended resets it
(its action is ignored, reward 0, not terminated or truncated), with
``autoreset_options`` (default: start at S, as a bare ``reset()`` of the single env).

``DiffDrive-v0``'s vector form (:class:`DiffDriveVectorEnv`) keeps N single envs whose
worlds share one :class:`sim.physics.world.SharedSpace`: each control period, every robot
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

from sim.grid import build_model
from sim.grid.env import start_state_from_options
from sim.physics.batch import RouteBatch
from sim.physics.envs import DIFFDRIVE_CONFIG, DiffDriveEnv, _scenario
from sim.physics.fidelity import Fidelity, parse_fidelity
from sim.physics.static import PhysicsConfig
from sim.physics.world import SharedSpace
from sim.scenario import Scenario


def sub_env_seeds(seed: int | list[int | None] | None, n: int) -> list[int | None]:
    """Gymnasium's rule: an int seeds sub-env i with seed + i; a list gives one per sub-env."""
    if seed is None:
        return [None] * n
    if isinstance(seed, int):
        return [seed + i for i in range(n)]
    seeds = list(seed)
    if len(seeds) != n:
        raise ValueError(f"{len(seeds)} seeds for {n} sub-envs")
    return seeds


class PhysicsRouteVectorEnv(VectorEnv):
    """N independent copies of ``PhysicsRoute-v0`` sharing one ``pymunk.Space``.

    Observations are ``int64[N]`` cells, actions ``int[N]`` in 0..3 (up, down, left,
    right). ``infos`` holds arrays over sub-envs (gymnasium's ``key`` / ``_key`` form):
    ``pose`` (N, 3) [m, m, rad], ``time_s`` [s], ``bumped``, ``reached``, ``timeout``,
    ``steps`` (physics steps of the primitive) and ``contacts`` (how many began).

    The route problem's episode rules live here and nowhere else: the reward
    (:meth:`sim.scenario.Rewards.of_moves`), termination on entering G, truncation after
    ``max_episode_steps`` primitives, and each sub-env's own noise stream. Physics training
    (:mod:`scenarios.runs.physics`) steps this env; a single run is ``num_envs=1``.

    ``autoreset_mode``: ``NEXT_STEP`` (gymnasium's default) or ``DISABLED``. With
    ``DISABLED`` the caller resets ended sub-envs itself (``reset(options={"reset_mask":
    m, "starts": s})``) and a sub-env whose episode ended and was not reset sits out every
    later step (observation unchanged, reward 0, neither terminated nor truncated, its
    ``_key`` masks False): a training loop whose runs finish at different times leaves them
    there. ``reset`` options: ``start`` (``"S"``, ``"random"`` or a state, for every reset
    sub-env), ``starts`` (``int[N]``, a start state per sub-env; only masked entries are
    read), ``reset_mask`` (``bool[N]``). ``trajectories=True`` keeps every physics step's
    pose of the last primitive (:meth:`trajectory`) for recordings.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}  # noqa: RUF012

    def __init__(self, num_envs: int = 1, scenario: str | Scenario = "paper-50",
                 config: PhysicsConfig | None = None, max_episode_steps: int | None = 600,
                 autoreset_options: dict[str, Any] | None = None,
                 render_mode: str | None = None,
                 fidelity: Fidelity | str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 trajectories: bool = False) -> None:
        if render_mode is not None:
            raise ValueError("PhysicsRouteVectorEnv does not render; use the single env")
        if not (isinstance(num_envs, int) and num_envs >= 1):
            raise ValueError(f"num_envs must be an int >= 1, got {num_envs!r}")
        mode = AutoresetMode(autoreset_mode)
        if mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.DISABLED):
            raise ValueError(f"autoreset_mode must be NEXT_STEP or DISABLED, got {mode!r}")
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        self.num_envs = num_envs
        self.scenario = _scenario(scenario)
        self.model = build_model(self.scenario)
        self.config = config or PhysicsConfig()
        self.config.validate()
        self.max_episode_steps = max_episode_steps
        self.autoreset_options = autoreset_options
        self.fidelity = (fidelity if isinstance(fidelity, Fidelity)
                         else parse_fidelity(fidelity if fidelity is not None
                                             else self.scenario.physics, "fidelity"))
        self.batch = RouteBatch(self.scenario, num_envs, self.config, fidelity=self.fidelity,
                                trajectories=trajectories)
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

    def set_noise_rng(self, i: int, rng: np.random.Generator) -> None:
        """Sub-env ``i`` draws its wheel noise from ``rng`` from now on, whatever seeds later
        resets get (a sweep gives each run its own physics stream)."""
        self.batch.set_noise_rng(int(i), rng)
        self._own_noise[i] = True

    def _reset_one(self, i: int, options: dict[str, Any] | None,
                   starts: np.ndarray | None = None) -> None:
        if starts is not None:
            s = int(starts[i])
            if not (0 <= s < self.model.n_states):
                raise ValueError(f"options['starts'][{i}] = {s} is not a state")
        else:
            s = start_state_from_options(options, self.model, self._rngs[i])
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
        mask = np.asarray(opts.pop("reset_mask", np.ones(self.num_envs, bool)), dtype=bool)
        starts = opts.pop("starts", None)
        if starts is not None:
            starts = np.asarray(starts, dtype=np.int64).reshape(self.num_envs)
        for i in np.flatnonzero(mask):
            if seeds[i] is not None:
                self._rngs[i] = seeding.np_random(seeds[i])[0]
            if not self._own_noise[i] and (seeds[i] is not None
                                           or self.batch._noise_rngs[i] is None):
                self.batch.set_noise_rng(int(i), self._rngs[i])  # as the single env does
            self._reset_one(int(i), opts or None, starts)
        return self._obs.copy(), self._infos(mask, None)

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        acts = np.asarray(actions, dtype=np.int64).reshape(self.num_envs)
        if ((acts < 0) | (acts > 3)).any():
            raise ValueError(f"actions must be in 0..3, got {acts.tolist()}")
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            resetting = self._needs_reset.copy()
            for i in np.flatnonzero(resetting):
                self._reset_one(int(i), self.autoreset_options)
            moving = ~resetting
        else:
            moving = ~self._needs_reset
        out = self.batch.step(acts, moving)
        obs = np.where(moving, out.state, self._obs)
        terminated = moving & (obs == self._goal)
        rewards = self._rewards.of_moves(out.bumped, terminated) * moving
        self._elapsed += moving
        truncated = (moving & (self._elapsed >= self.max_episode_steps)
                     if self.max_episode_steps is not None else np.zeros_like(moving))
        self._obs[:] = obs
        if self.autoreset_mode == AutoresetMode.DISABLED:
            self._needs_reset |= terminated | truncated  # idle until the caller resets
            mask = moving
        else:
            self._needs_reset = terminated | truncated
            mask = np.ones(self.num_envs, bool)
        return obs.copy(), rewards.astype(np.float64), terminated, truncated, \
            self._infos(mask, out)

    def trajectory(self, i: int) -> np.ndarray:
        """float64[n, 3]: sub-env ``i``'s pose before its last primitive, then after each
        physics step of it (needs ``trajectories=True``)."""
        return self.batch.trajectory(int(i))

    def contact_records(self, i: int) -> list[Any]:
        """Sub-env ``i``'s contacts (:class:`sim.physics.Contact`) since its last reset."""
        return self.batch.contacts[int(i)]

    def _infos(self, mask: np.ndarray, out: Any) -> dict[str, Any]:
        b = self.batch
        pose = b.poses()
        pose[:, 2] = (pose[:, 2] + np.pi) % (2.0 * np.pi) - np.pi  # as wrap_angle
        infos: dict[str, Any] = {
            "pose": pose, "time_s": b.r.steps * self.config.dt_s,
            "bumped": np.zeros(self.num_envs, bool) if out is None else out.bumped,
            "reached": np.zeros(self.num_envs, bool) if out is None else out.reached,
            "timeout": np.zeros(self.num_envs, bool) if out is None else out.timeout,
            "steps": np.zeros(self.num_envs, np.int64) if out is None else out.steps,
            "contacts": np.zeros(self.num_envs, np.int64) if out is None else out.contacts,
        }
        for k in list(infos):
            infos[f"_{k}"] = mask.copy()
        return infos


class DiffDriveVectorEnv(VectorEnv):
    """N copies of ``DiffDrive-v0`` (wheel speeds in, pose out) stepping in one Space.

    Observations ``float32[N, 8]``, actions ``float32[N, 2]`` (left, right wheel speed
    [m/s]); ``infos`` hold ``pose`` (N, 3), ``time_s``, ``state``, ``in_contact`` and
    ``contacts`` (how many began) with gymnasium's ``_key`` masks.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}  # noqa: RUF012

    def __init__(self, num_envs: int = 1, scenario: str | Scenario = "paper-50",
                 config: PhysicsConfig | None = None, max_episode_steps: int | None = 2000,
                 autoreset_options: dict[str, Any] | None = None,
                 render_mode: str | None = None) -> None:
        if render_mode is not None:
            raise ValueError("DiffDriveVectorEnv does not render; use the single env")
        if not (isinstance(num_envs, int) and num_envs >= 1):
            raise ValueError(f"num_envs must be an int >= 1, got {num_envs!r}")
        self.num_envs = num_envs
        sc = _scenario(scenario)
        self.config = config or DIFFDRIVE_CONFIG
        self.shared = SharedSpace(sc, self.config)
        self.envs = [DiffDriveEnv(sc, config=self.config, shared=self.shared)
                     for _ in range(num_envs)]
        self.max_episode_steps = max_episode_steps
        self.autoreset_options = autoreset_options
        self.single_observation_space = self.envs[0].observation_space
        self.single_action_space = self.envs[0].action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._obs = np.zeros((num_envs, 8), dtype=np.float32)
        self._elapsed = np.zeros(num_envs, dtype=np.int64)
        self._needs_reset = np.ones(num_envs, dtype=bool)

    def reset(self, *, seed: int | list[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        seeds = sub_env_seeds(seed, self.num_envs)
        opts = dict(options or {})
        mask = np.asarray(opts.pop("reset_mask", np.ones(self.num_envs, bool)), dtype=bool)
        infos = [None] * self.num_envs
        for i in np.flatnonzero(mask):
            self._obs[i], infos[i] = self.envs[i].reset(seed=seeds[i], options=opts or None)
            self._elapsed[i] = 0
            self._needs_reset[i] = False
        return self._obs.copy(), self._infos(mask, infos)

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        acts = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, 2)
        resetting = self._needs_reset.copy()
        infos: list[Any] = [None] * self.num_envs
        for i in np.flatnonzero(resetting):
            self._obs[i], infos[i] = self.envs[i].reset(options=self.autoreset_options)
            self._elapsed[i] = 0
        moving = [self.envs[i] for i in np.flatnonzero(~resetting)]
        for i in np.flatnonzero(~resetting):
            self.envs[i].begin_period(acts[i])
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
        for i in np.flatnonzero(~resetting):
            self._obs[i], rewards[i], terminated[i], _, infos[i] = self.envs[i].end_period()
        self._elapsed += ~resetting
        truncated = (~resetting & (self._elapsed >= self.max_episode_steps)
                     if self.max_episode_steps is not None else np.zeros(self.num_envs, bool))
        self._needs_reset = terminated | truncated
        return self._obs.copy(), rewards, terminated, truncated, \
            self._infos(np.ones(self.num_envs, bool), infos)

    def _infos(self, mask: np.ndarray, per_env: list[Any]) -> dict[str, Any]:
        n = self.num_envs
        out: dict[str, Any] = {"pose": np.zeros((n, 3)), "time_s": np.zeros(n),
                               "state": np.zeros(n, np.int64), "in_contact": np.zeros(n, bool),
                               "contacts": np.zeros(n, np.int64)}
        for i, info in enumerate(per_env):
            if info is None:
                continue
            out["pose"][i] = info["pose"]
            out["time_s"][i] = info["time_s"]
            out["state"][i] = info["state"]
            out["in_contact"][i] = info.get("in_contact", False)
            out["contacts"][i] = len(info["contacts"])
        for k in list(out):
            out[f"_{k}"] = mask.copy()
        return out

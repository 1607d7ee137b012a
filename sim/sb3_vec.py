"""A gymnasium vector env as a Stable-Baselines3 ``VecEnv`` (needs ``pip install rnhql[sb3]``).

Why: SB3 steps N envs through its own ``VecEnv`` API (``DummyVecEnv`` steps N Python envs
in turn); the native vector envs of ``rnhql/PhysicsRoute-v0`` and ``rnhql/DiffDrive-v0``
step N robots in one Pymunk Space, in one compiled call for the route primitives. This
adapter lets SB3 train on them directly::

    import gymnasium as gym
    import sim
    from sim.sb3_vec import SB3VecEnv
    from stable_baselines3 import DQN

    venv = SB3VecEnv(gym.make_vec("rnhql/PhysicsRoute-v0", 8,
                                  vectorization_mode="vector_entry_point",
                                  scenario="rooms-102", autoreset_mode="SameStep"))
    DQN("MlpPolicy", venv, seed=0).learn(10_000)

It works over any gymnasium ``VectorEnv`` in the ``SAME_STEP`` autoreset mode (SB3's
convention: the step that ends an episode returns the next episode's first observation,
the last one goes to ``infos[i]["terminal_observation"]``; a truncation that is not a
termination sets ``infos[i]["TimeLimit.truncated"]``, so SB3 bootstraps through it).
``infos[i]`` holds sub-env ``i``'s entries of the vector env's ``info`` (the ended
episode's last step for a sub-env that ended). Stable-Baselines3 is imported here only,
so the rest of ``sim`` works without it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

# what a single env calls an attribute -> the name a native vector env keeps it under
SHARED_ALIASES = {"rewards": "_rewards", "steps_per_episode": "max_episode_steps"}


def _row(info: dict[str, Any], i: int) -> dict[str, Any]:
    """Sub-env ``i``'s entries of a vector ``info`` (keys whose ``_key`` mask is set)."""
    out: dict[str, Any] = {}
    for k, v in info.items():
        if k.startswith("_") or k in ("final_obs", "final_info"):
            continue
        mask = info.get(f"_{k}")
        if mask is None or mask[i]:
            out[k] = v[i] if not isinstance(v, dict) else _row(v, i)
    return out


class SB3VecEnv(VecEnv):
    """Stable-Baselines3's ``VecEnv`` over a gymnasium ``VectorEnv`` (``SAME_STEP`` mode).

    ``venv``: e.g. ``gymnasium.make_vec(id, n, vectorization_mode="vector_entry_point",
    autoreset_mode="SameStep")``; a vector env in another mode is refused with the fix.
    Seeds and options follow SB3's rules (``seed(s)`` before ``reset()`` seeds sub-env
    ``i`` with ``s + i``; ``set_options`` applies at the next reset). ``get_attr`` and
    ``env_method`` reach the sub-envs where the vector env keeps them (``.envs``), else
    the vector env itself, once per index.
    """

    def __init__(self, venv: VectorEnv) -> None:
        mode = venv.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"SB3VecEnv needs a vector env in the SAME_STEP autoreset mode "
                             f"(SB3's convention), got {mode!r}: make it with "
                             "autoreset_mode='SameStep' (native vector envs) or "
                             "vector_kwargs={'autoreset_mode': AutoresetMode.SAME_STEP}")
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space,
                         venv.single_action_space)
        self._actions: np.ndarray | None = None
        self.reset_infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]

    # ---------------------------------------------------------------- stepping
    def reset(self) -> np.ndarray:
        opts = self._options
        if any(o != opts[0] for o in opts):
            raise ValueError("SB3VecEnv passes one options dict to every sub-env; "
                             "set_options(dict) rather than a list of different ones")
        obs, info = self.venv.reset(seed=list(self._seeds), options=opts[0] or None)
        self.reset_infos = [_row(info, i) for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        if self._actions is None:
            raise RuntimeError("step_wait() without step_async()")
        obs, rewards, terminated, truncated, info = self.venv.step(self._actions)
        self._actions = None
        dones = terminated | truncated
        infos = [_row(info, i) for i in range(self.num_envs)]
        final_obs, final_info = info.get("final_obs"), info.get("final_info")
        for i in np.flatnonzero(dones):
            if final_info is not None:
                self.reset_infos[i] = infos[i]  # what the new episode started with
                infos[i] = _row(final_info, i)
            infos[i]["terminal_observation"] = (final_obs[i] if final_obs is not None
                                                else obs[i])
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    # ---------------------------------------------------------------- attributes
    def _targets(self, indices: VecEnvIndices) -> list[Any]:
        subs = getattr(self.venv.unwrapped, "envs", None)
        return [subs[i] if subs is not None else self.venv.unwrapped
                for i in self._get_indices(indices)]

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """Sub-env ``i``'s attribute for each index, as ``DummyVecEnv`` answers it; on a
        native vector env (one object for every robot) what the robots share, by the
        single env's names (``scenario``, ``rewards``, ``steps_per_episode``, ...)."""
        if attr_name == "render_mode":
            return [None for _ in self._get_indices(indices)]
        out = []
        for t in self._targets(indices):
            name = attr_name
            if not hasattr(t, name) and hasattr(t, SHARED_ALIASES.get(name, "")):
                name = SHARED_ALIASES[name]
            if not hasattr(t, name):
                raise AttributeError(f"{type(t).__name__} has no attribute {attr_name!r}; "
                                     "it answers scenario, model, config, fidelity, start, "
                                     f"{', '.join(SHARED_ALIASES)} and its own attributes")
            out.append(getattr(t, name))
        return out

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        for t in self._targets(indices):
            setattr(t, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        """Call a method of each indexed sub-env. On a native vector env ``reset`` resets
        only the indexed robots (``reset_mask``) and returns each one's ``(obs, info)``, as
        the single envs' resets would."""
        if method_name == "reset" and getattr(self.venv.unwrapped, "envs", None) is None:
            idx = list(self._get_indices(indices))
            mask = np.zeros(self.num_envs, bool)
            mask[idx] = True
            opts = dict(method_kwargs.pop("options", None) or {})
            seed = method_kwargs.pop("seed", None)
            if method_args or method_kwargs:
                raise TypeError("reset takes only seed= and options=")
            seeds = None if seed is None else [seed if m else None for m in mask]
            obs, info = self.venv.reset(seed=seeds, options={**opts, "reset_mask": mask})
            return [(obs[i], _row(info, i)) for i in idx]
        return [getattr(t, method_name)(*method_args, **method_kwargs)
                for t in self._targets(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None
                       ) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.num_envs)]

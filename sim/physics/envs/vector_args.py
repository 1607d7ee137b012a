"""What both physics vector envs take and check first: the autoreset mode, the batch's
size, each sub-env's seed and the ``reset_mask`` option (a module of its own so that the
envs' module holds the envs)."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from sim.env_args import INTEGER_KINDS, check_num_envs


def autoreset_mode_arg(mode: AutoresetMode | str) -> AutoresetMode:
    """One of gymnasium's :class:`AutoresetMode` (or its value, ``"NextStep"``, ...)."""
    try:
        return AutoresetMode(mode)
    except ValueError:
        raise ValueError(f"autoreset_mode must be one of "
                         f"{', '.join(repr(m.value) for m in AutoresetMode)} (gymnasium."
                         f"vector.AutoresetMode), got {mode!r}") from None


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


def reset_mask_option(options: dict[str, Any], n: int) -> np.ndarray:
    """Pop ``reset(options={"reset_mask": m})``: bool[n], the sub-envs to reset (every one
    without the option). ``m`` holds exactly ``n`` booleans (or 0/1 integers); a shorter
    or longer mask (numpy would broadcast it), a float or a 2 (which a cast calls True) is
    an error."""
    if "reset_mask" not in options:
        return np.ones(n, bool)
    value = options.pop("reset_mask")
    try:
        m = np.asarray(value)
    except (TypeError, ValueError):  # a ragged list
        m = np.asarray(None)
    if not (m.shape == (n,) and (m.dtype == bool or (m.dtype.kind in INTEGER_KINDS
                                                     and ((m == 0) | (m == 1)).all()))):
        raise ValueError(f"options['reset_mask'] must be {n} booleans (bool[{n}], or 0/1 "
                         f"integers), one per sub-env, got {value!r}; pass e.g. "
                         f"np.ones({n}, dtype=bool)")
    return m.astype(bool)


def vector_setup(env: Any, num_envs: int, render_mode: str | None,
                  autoreset_mode: AutoresetMode | str) -> int:
    """What both vector envs check and set first: no rendering, a bounded batch (returned
    as an int), the autoreset mode in the env's metadata."""
    if render_mode is not None:
        raise ValueError(f"{type(env).__name__} does not render; use the single env")
    num_envs = check_num_envs(num_envs)
    env.metadata = {**type(env).metadata, "autoreset_mode": autoreset_mode_arg(autoreset_mode)}
    env.num_envs = num_envs
    return num_envs

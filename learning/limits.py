"""Upper limits on the config fields that set how much work or memory a run takes.

Why a module of its own: a config's own checks (:mod:`learning.config`) say what a value
*means* (``k >= 1``); these say what a machine can *do*. ``--set k=1e30`` is a valid
number of RBF centres per axis and a request for more memory than exists, and
``n_planning=1e12`` a run that never ends. Both the command line (``--set``) and a
checkpoint's stored config are checked here, before any array is allocated, so the
error names the field and its limit instead of a traceback or a hang. Non-finite
values are refused for every float field (a field that means "never" uses None).
"""

from __future__ import annotations

import math

# field -> (largest value, what it is); far beyond every study, far below exhaustion
LIMITS: dict[str, tuple[float, str]] = {
    "k": (100, "RBF centres per axis (k x k features per state)"),
    "n_planning": (10_000, "planning updates per real step"),
    "n_fit": (10_000, "network fits per real step"),
    "block": (4096, "abstract cell side [cells]"),
    "spacing": (4096, "RBF centre spacing [cells]"),
    "warmup_episodes": (10_000_000, "episodes"),
    "freeze_after_episodes": (10_000_000, "episodes"),
}
# floats are refused beyond this magnitude: a value no reward scale or rate needs, and
# one that overflows to inf in the first update
MAX_MAGNITUDE = 1e100


def limit_problem(name: str, value: object) -> str | None:
    """Why ``value`` of the config field ``name`` is beyond what a run can do, or None."""
    if value is None or isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        if isinstance(value, float) and not math.isfinite(value):
            return f"{name} = {value} is not a finite number"
        if name in LIMITS and value > LIMITS[name][0]:
            limit, what = LIMITS[name]
            return f"{name} = {value:g} is more than the limit {limit:,g} ({what})"
        if abs(value) > MAX_MAGNITUDE:
            return f"{name} = {value:g} is beyond the limit of {MAX_MAGNITUDE:g} in magnitude"
    return None


def config_problem(fields: dict[str, object]) -> str | None:
    """The first field of a config (``{name: value}``) over its limit, as a sentence."""
    for name, value in fields.items():
        problem = limit_problem(name, value)
        if problem is not None:
            return problem
    return None

"""What every method's config has: the frozen dataclass base, its checks, and its parameters.

A config is pure data (units and meaning in the field comments). Its
:meth:`MethodConfig.params` is the same data as a named tuple of scalars, which
is what the compiled rules read (``st.par.alpha``): numba types a named tuple's
fields by name, so a rule says which parameter it uses.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar, NamedTuple, get_type_hints

# field -> (valid?, what a valid value is); checked for every config that has the field
_VALID = {
    "eps": (lambda v: 0.0 <= v <= 1.0, "in [0, 1]"),
    "alpha": (lambda v: 0.0 < v <= 1.0, "in (0, 1]"),
    "gamma": (lambda v: 0.0 < v <= 1.0, "in (0, 1]"),
    "lam": (lambda v: 0.0 <= v <= 1.0, "in [0, 1]"),
    "k": (lambda v: v >= 1, ">= 1"),
    "spacing_m": (lambda v: v >= 0.0, ">= 0 (0: k x k centres)"),
    "block": (lambda v: v >= 1, ">= 1"),
    "n_planning": (lambda v: v >= 0, ">= 0"),
    "warmup_episodes": (lambda v: v >= 0, ">= 0"),
    "freeze_after_episodes": (lambda v: v >= 0, ">= 0 or None"),
    "beta": (lambda v: v > 0.0, "> 0"),
    "alpha_v": (lambda v: 0.0 < v <= 1.0, "in (0, 1]"),
    "q_scale": (lambda v: v > 0.0, "> 0"),
    "trace_min": (lambda v: v > 0.0, "> 0"),
    "init_range": (lambda v: v > 0.0, "> 0"),
    "spacing": (lambda v: v >= 0, ">= 0"),
    "sigma": (lambda v: v > 0.0, "> 0"),
    "cutoff": (lambda v: v >= 0.0, ">= 0 (0: no cut-off)"),
    "normalise": (lambda v: v in (0, 1), "0 or 1"),
    "v_target": (lambda v: v in (0, 1, 2, 3, 4, 5), "0 (TD on rewards), 1 (max_a Q + Phi), 2 "
                 "(its log), 3 (log of the optimistic model's value), 4 (that value, no "
                 "network), 5 (log of max_a Q + Phi over that value)"),
    "shaping_scale": (lambda v: v >= 0.0, ">= 0"),
    "lam_q": (lambda v: 0.0 <= v <= 1.0, "in [0, 1]"),
    "leak_free": (lambda v: v in (0, 1), "0 or 1"),
    "rebase": (lambda v: v in (0, 1), "0 or 1"),
    "lookahead": (lambda v: v in (0, 1), "0 or 1"),
    "n_fit": (lambda v: v >= 0, ">= 0"),
    "explored": (lambda v: v in (0, 1), "0 or 1"),
    "known_route": (lambda v: v in (0, 1), "0 or 1"),
    "sweeping": (lambda v: v in (0, 1), "0 or 1"),
    "model_acting": (lambda v: v in (0, 1), "0 or 1"),
    "model_test": (lambda v: v in (0, 1), "0 or 1"),
    "explore_steps": (lambda v: v >= -1, ">= 0 [steps per episode], or -1: "
                      "4 x the arena's longer side"),
}


class FieldMovedError(ValueError):
    """A config field a method no longer has, set to a value it no longer runs: the setting
    now belongs to another method (the message names it)."""


def params_tuple(name: str, module: str, **fields: type) -> type:
    """The named tuple type ``name`` of a method's parameters: ``eps``, ``alpha`` and
    ``gamma`` (what every method reads), then ``fields`` (field -> float, int or bool, the
    type its rule expects), for :meth:`MethodConfig.params`. ``module``: the declaring
    module's ``__name__`` (the tuple pickles by it)."""
    kind = NamedTuple(name, [("eps", float), ("alpha", float), ("gamma", float),
                             *fields.items()])
    kind.__module__ = module
    return kind


# the parameters every method reads (methods with more declare their own tuple)
BaseParams = params_tuple("BaseParams", __name__)


@dataclass(frozen=True)
class MethodConfig:
    """Fields every method has. Episodes are 0-based; rewards are the env's."""

    name: ClassVar[str] = "?"  # paper/display name
    cli: ClassVar[str] = "?"  # CLI name, the key in learning.methods.registry.METHODS

    eps: float = 0.1  # probability of a uniformly random action (epsilon-greedy)
    alpha: float = 0.1  # Q learning rate (step size on the TD error)
    gamma: float = 0.95  # discount per step

    params_type: ClassVar[type] = BaseParams  # what params() returns (see params_tuple)
    # fields a method inherits from the config it extends but whose rules do not read them:
    # any value but the default is refused (a run must never record a setting it ignored)
    IGNORED: ClassVar[tuple[str, ...]] = ()

    def __post_init__(self) -> None:
        for name in self.IGNORED:
            default = next(f.default for f in dataclasses.fields(self) if f.name == name)
            if getattr(self, name) != default:
                raise ValueError(f"{type(self).__name__}.{name} = {getattr(self, name)!r}: "
                                 f"{self.cli}'s rules do not read {name}; leave it at "
                                 f"{default!r}, or use {self.reader_of(name)}")
        for f in dataclasses.fields(self):
            if f.name in _VALID:
                ok, what = _VALID[f.name]
                v = getattr(self, f.name)
                if v is not None and not ok(v):
                    raise ValueError(f"{type(self).__name__}.{f.name} = {v!r} must be {what}")

    @classmethod
    def reader_of(cls, name: str) -> str:
        """The nearest config this one extends whose rules read ``name`` (its CLI name)."""
        for base in cls.__mro__[1:]:
            if isinstance(base, type) and issubclass(base, MethodConfig) and \
                    name not in base.IGNORED and base.cli != "?":
                return base.cli
        return "a method that has it"

    @classmethod
    def settable(cls) -> tuple[str, ...]:
        """The fields ``--set`` may change: every field but the :attr:`IGNORED` ones."""
        return tuple(f.name for f in dataclasses.fields(cls) if f.name not in cls.IGNORED)

    def params(self) -> NamedTuple:
        """The fields the compiled rules read, as a named tuple of float/int/bool scalars
        (:attr:`params_type`: each field cast to the type its rule expects, so a ``--set``
        value never changes the compiled signature)."""
        kind = self.params_type
        return kind(*(cast(getattr(self, f)) for f, cast in get_type_hints(kind).items()))

    def fields(self) -> dict[str, object]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def record_fields(self) -> dict[str, object]:
        """What a run's record lists as its config: the fields (a method may add settings it
        has fixed, see :meth:`learning.methods.rnh_ql_plus.RNHQLPlus.record_fields`)."""
        return self.fields()

    @classmethod
    def from_fields(cls, values: dict[str, object]) -> MethodConfig:
        """The config of these field values (e.g. a checkpoint's)."""
        return cls(**values)


# ---------------------------------------------------------------- limits
# Upper limits on the fields that set how much work or memory a run takes. The checks
# above say what a value *means* (``k >= 1``); these say what a machine can *do*.
# ``--set k=1e30`` is a valid number of RBF centres per axis and a request for more memory
# than exists, and ``n_planning=1e12`` a run that never ends. The command line (``--set``)
# and a checkpoint's stored config are both checked here, before any array is allocated,
# so the error names the field and its limit instead of a traceback or a hang. Non-finite
# values are refused for every float field (a field that means "never" uses None).

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

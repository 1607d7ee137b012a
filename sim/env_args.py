"""The arguments every rnhql env takes, resolved in one place.

Why one module: the three ids and their vector forms take the same ``scenario``,
``rewards``, ``fidelity``, ``config`` and episode length, from three kinds of caller --
Python objects (a :class:`sim.scenario.Scenario`, a :class:`sim.scenario.Rewards`), names
(``"paper-50"``, ``"goal-only"``, ``"noisy"``) and the plain dicts that a spec's JSON round
trip leaves (``EnvSpec.to_json`` turns every dataclass in ``kwargs`` into a dict, and
``json`` turns tuples into lists). Each is turned back into the frozen dataclass here, so
``gymnasium.make(EnvSpec.from_json(env.spec.to_json()))`` builds the same env, and bad
input stops with a :class:`sim.errors.ScenarioError` that names the argument and the fix.

Actions are checked here too: a client such as Stable-Baselines3 passes a 0-d integer
array for a ``Discrete`` action and a float64 array for a ``Box`` one (numpy's default);
both are what the spaces mean, so both are accepted.
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any

import numpy as np

from sim.errors import ScenarioError
from sim.scenario import Circle, Rewards, Robot, Scenario, rewards_from_text

SOURCE = "env argument"
# The scheme gymnasium.make / make_vec give (sim/envs.py registers it as the ids' default):
# with the paper's +1 per free step a deep-RL learner at gamma = 0.99 earns more by
# wandering 600 steps (+600) than by reaching G (+100), and does.
DEFAULT_REWARDS = "goal-only"
SCENARIO_REWARDS = "scenario"  # rewards="scenario": the scenario's own [rewards] table


class InvalidAction(ValueError, AssertionError):
    """An action outside the env's action space. A ``ValueError`` (bad input) that is also
    the ``AssertionError`` Gymnasium's own envs raise for one, so either ``except`` works."""


def _tuple_of(cls: type, items: Any, fld: str) -> tuple:
    if not isinstance(items, list | tuple):
        raise ScenarioError(SOURCE, fld, f"expected a list, got {items!r}",
                            "pass a Scenario, a scenario name or Scenario's fields as a dict")
    return tuple(_dataclass_of(cls, x, f"{fld}[{i}]") if isinstance(x, dict) else x
                 for i, x in enumerate(items))


def _dataclass_of(cls: type, value: Any, fld: str) -> Any:
    """``cls(**value)`` for a dict of its fields (what ``dataclasses.asdict`` made of it)."""
    if isinstance(value, cls):
        return value
    if not isinstance(value, dict):
        raise ScenarioError(SOURCE, fld, f"expected a {cls.__name__} or a dict of its "
                            f"fields, got {value!r}", f"pass a {cls.__name__}")
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(value) - names)
    if unknown:
        raise ScenarioError(SOURCE, f"{fld}.{unknown[0]}", f"is not a field of {cls.__name__}",
                            f"use only {', '.join(sorted(names))}")
    try:
        return cls(**value)
    except TypeError as err:
        raise ScenarioError(SOURCE, fld, str(err), f"give every field of {cls.__name__}") \
            from None


def scenario_source(value: Any) -> Any:
    """``value`` with a path object (``pathlib.Path``, any ``os.PathLike``) as the ``str``
    path it names; anything else as given (a name, a Scenario, a dict)."""
    if isinstance(value, os.PathLike):
        path = os.fspath(value)
        return path if isinstance(path, str) else value
    return value


def scenario_arg(value: Any) -> Scenario:
    """A built-in name or ``.toml`` path (loaded and validated), a :class:`Scenario`, or a
    dict of a Scenario's fields (validated): the scenario an env is built on."""
    from sim.feasibility import validate
    from sim.scenario_io import resolve_scenario

    value = scenario_source(value)
    if isinstance(value, str):
        return resolve_scenario(value)
    if isinstance(value, dict):
        d = dict(value)
        for key in ("start", "goal"):
            if isinstance(d.get(key), list):
                d[key] = tuple(d[key])
        if "obstacles" in d:
            d["obstacles"] = _tuple_of(Circle, d["obstacles"], "scenario.obstacles")
        if "blocked_cells" in d:
            d["blocked_cells"] = tuple(tuple(c) for c in d["blocked_cells"])
        if isinstance(d.get("robot"), dict):
            d["robot"] = _dataclass_of(Robot, d["robot"], "scenario.robot")
        if isinstance(d.get("rewards"), dict):
            d["rewards"] = _dataclass_of(Rewards, d["rewards"], "scenario.rewards")
        value = _dataclass_of(Scenario, d, "scenario")
    if not isinstance(value, Scenario):
        raise ScenarioError(SOURCE, "scenario", f"expected a name, a .toml path or a Scenario, "
                            f"got {value!r}", "use e.g. scenario='paper-50' (`rnhql scenarios` "
                            "lists the names)")
    validate(value)
    return value


def rewards_arg(value: Any, sc: Scenario) -> Rewards:
    """``"scenario"`` (the scenario's own scheme), a preset name (``"paper"``,
    ``"goal-only"``, ``"step-cost"``), ``"goal=100,bump=-1,step=0"``, a :class:`Rewards`
    or a dict of its fields."""
    if value is None or value == SCENARIO_REWARDS:
        return sc.rewards
    if isinstance(value, str):
        return rewards_from_text(value, "rewards")
    rw = _dataclass_of(Rewards, value, "rewards")
    for name in ("goal", "bump", "step"):
        v = getattr(rw, name)
        if not (isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)):
            raise ScenarioError(SOURCE, f"rewards.{name}", f"must be a finite number, got {v!r}",
                                "use e.g. Rewards.preset('goal-only')")
    return rw.named()


def env_scenario(scenario: Any, rewards: Any) -> Scenario:
    """The scenario an env runs: resolved, with the reward scheme it pays put in it (so
    ``env.scenario.rewards`` and the tabular model ``env.model`` say what the env pays)."""
    sc = scenario_arg(scenario)
    rw = rewards_arg(rewards, sc)
    return sc if rw == sc.rewards else dataclasses.replace(sc, rewards=rw)


def fidelity_arg(value: Any, sc: Scenario) -> Any:
    """``None`` (the scenario's ``[physics]`` table, else ``exact``), a preset or
    ``"noisy,wheel_noise=0.1"`` text, a :class:`sim.physics.fidelity.Fidelity` or a dict."""
    from sim.physics.fidelity import Fidelity, parse_fidelity

    if value is None:
        return parse_fidelity(sc.physics, f"{sc.source}: [physics]")
    if isinstance(value, str):
        return parse_fidelity(value, "fidelity")
    fid = _dataclass_of(Fidelity, value, "fidelity")
    fid.validate("fidelity")
    return fid


def config_arg(value: Any, default: Any) -> Any:
    """A :class:`sim.physics.static.PhysicsConfig`, a dict of its fields, or ``None``
    (``default``); validated."""
    from sim.physics.static import PhysicsConfig

    cfg = default if value is None else _dataclass_of(PhysicsConfig, value, "config")
    cfg.validate()
    return cfg


class SpecOwnLimit:
    """Mixin of the envs that truncate themselves: the ``spec`` ``gymnasium.make`` gives them
    says so (``max_episode_steps`` = the env's ``steps_per_episode``), so a client that reads
    the spec sees the limit. Registered without one, so ``make`` adds no ``TimeLimit``."""

    _spec: Any = None

    @property
    def spec(self) -> Any:
        return self._spec

    @spec.setter
    def spec(self, value: Any) -> None:
        limit = getattr(self, "steps_per_episode", None)
        if value is not None and value.max_episode_steps is None and limit is not None:
            value = dataclasses.replace(value, max_episode_steps=int(limit))
        if value is not None and isinstance(value.kwargs.get("scenario"), os.PathLike):
            # a Path as the str it names, so the spec's JSON round trip rebuilds the env
            value = dataclasses.replace(value, kwargs={
                **value.kwargs, "scenario": scenario_source(value.kwargs["scenario"])})
        self._spec = value


MAX_NUM_ENVS = 4096  # robots in one vector env: 100,000 took 24 GB and was killed


def check_num_envs(num_envs: object) -> int:
    """A vector env's robot count (an int or a numpy integer) as an int, refused beyond
    :data:`MAX_NUM_ENVS` (each robot holds its own state in one Space)."""
    if not (isinstance(num_envs, int | np.integer) and not isinstance(num_envs, bool)
            and 1 <= num_envs <= MAX_NUM_ENVS):
        raise ScenarioError(SOURCE, "num_envs", f"must be an int in 1..{MAX_NUM_ENVS:,} "
                            f"(robots in one Space; each holds its own state), got "
                            f"{num_envs!r}", "use fewer envs per vector env, or "
                            "several vector envs")
    return int(num_envs)


def episode_limit(value: Any, default: int, fld: str = "steps_per_episode") -> int:
    """An episode length in env steps: ``value``, or ``default`` (from the scenario)."""
    if value is None:
        return int(default)
    if not (isinstance(value, int | np.integer) and not isinstance(value, bool) and value >= 1):
        raise ScenarioError(SOURCE, fld, f"must be an integer >= 1, got {value!r}",
                            f"use e.g. {fld}=600, or leave it out for the scenario's")
    return int(value)


def finite_real(value: Any, fld: str, fix: str) -> float:
    """A finite real number as a float: an int, a float or a numpy integer / floating
    scalar. A bool, a string (``"1.0"``), an array or a non-finite value is an error naming
    ``fld``, not a number ``float()`` made of it."""
    if not (isinstance(value, int | float | np.integer | np.floating)
            and not isinstance(value, bool)):
        raise ValueError(f"{fld} must be a real number (int or float), got {value!r} "
                         f"({type(value).__name__}); {fix}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{fld} must be finite, got {value!r}; {fix}")
    return v


# numpy dtype kinds an action array may have: signed, unsigned integers (and floats for a
# Box). Never object (numpy would convert each element: "0.5", True and 1.7 alike), bool,
# complex or text; gymnasium's own spaces refuse those arrays too.
INTEGER_KINDS = "iu"
REAL_KINDS = "iuf"


def _action_array(value: Any, what: str) -> np.ndarray:
    try:
        return np.asarray(value)
    except (TypeError, ValueError):  # a ragged list
        raise InvalidAction(f"{what} {value!r} is not an array of numbers") from None


def discrete_action(action: Any, n: int) -> int:
    """An action of ``Discrete(n)`` as a Python int: an int, a numpy integer, or an integer
    array holding one value (``model.predict`` returns a 0-d one)."""
    a = action
    if isinstance(a, np.ndarray):
        if a.size != 1 or a.dtype.kind not in INTEGER_KINDS:
            raise InvalidAction(f"action {a!r} is not one integer in 0..{n - 1}")
        a = a.reshape(())[()]
    if not (isinstance(a, int | np.integer) and not isinstance(a, bool | np.bool_)):
        raise InvalidAction(f"action {action!r} ({type(action).__name__}) is not an integer "
                            f"in 0..{n - 1} (0 up, 1 down, 2 left, 3 right)")
    if not 0 <= a < n:
        raise InvalidAction(f"action {int(a)} is not in 0..{n - 1} "
                            "(0 up, 1 down, 2 left, 3 right)")
    return int(a)


def discrete_actions(actions: Any, n: int, num_envs: int) -> np.ndarray:
    """A vector env's batch of ``Discrete(n)`` actions as int64[num_envs] (a copy): an
    integer array (any integer dtype; ``num_envs`` values, reshaped) or a list of ints.
    A float, bool or object array is refused as the single env refuses a float or a bool:
    a cast would drive 1.7 as 1."""
    a = _action_array(actions, "actions")
    if a.size != num_envs or a.dtype.kind not in INTEGER_KINDS:
        raise InvalidAction(f"actions must be {num_envs} integers in 0..{n - 1} (0 up, 1 down, "
                            f"2 left, 3 right), one per sub-env, got {a.tolist()!r} of dtype "
                            f"{a.dtype}; pass an integer array, e.g. np.array(actions, "
                            "dtype=np.int64)")
    a = a.astype(np.int64).reshape(num_envs)
    if ((a < 0) | (a >= n)).any():
        raise InvalidAction(f"actions must be in 0..{n - 1} (0 up, 1 down, 2 left, 3 right), "
                            f"got {a.tolist()}")
    return a


def real_actions(actions: Any, shape: tuple[int, ...], what: str = "action") -> np.ndarray:
    """``Box`` actions of ``shape`` as float64: an array of any real dtype (float64 is what
    numpy and most clients hand over, float32 the space's) or a list of numbers; one of the
    same size is reshaped. An object, bool or text array is refused, not converted."""
    a = _action_array(actions, what)
    if a.dtype.kind not in REAL_KINDS:
        raise InvalidAction(f"{what} must be numbers (an int or float array), got "
                            f"{a.tolist()!r} of dtype {a.dtype}; pass a float array, e.g. "
                            "np.array([0.5, 0.5], dtype=np.float32)")
    if a.shape != shape:
        if a.size != math.prod(shape):
            raise InvalidAction(f"{what} has shape {a.shape}, expected {shape} "
                                "(left, right wheel speed [m/s])")
        a = a.reshape(shape)
    return a.astype(np.float64, copy=False)


def box_action(action: Any, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """A ``Box`` action as float64, clipped to ``[low, high]`` (a wheel cannot turn faster
    than its motor: a command beyond the limit drives at the limit, as on a robot). Any
    real dtype is accepted (:func:`real_actions`); a wrong shape, an object array or a
    non-finite value is an error."""
    a = real_actions(action, low.shape)
    if not np.isfinite(a).all():
        raise InvalidAction(f"action {a.tolist()} is not finite")
    return np.clip(a, low, high)

"""The arguments of :mod:`scenarios.api`, checked before any work: each helper returns the
value as a sweep holds it (text, a name, a cell) or raises :class:`sim.errors.InputError`
naming the function, the argument and the fix. These are the only checks: the command
passes its flags here and says a refusal in flag words (:func:`scenarios.cli.args.flag_words`)."""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from learning.config import MethodConfig
from learning.methods.registry import METHODS, comparison_methods
from learning.plain.batched import is_batched
from learning.plain.learner import located_name, remember
from scenarios.memory_limit import recording_refused
from scenarios.runs.spec import WORLDS, load, method_class, physics_budget
from scenarios.sweep.outdir import check_output_file
from sim.env_args import DEFAULT_REWARDS  # the one default (the envs', the command's, ours):

#                                          goal-only; the paper's own is rewards="paper"
from sim.errors import InputError
from sim.files import check_output
from sim.physics.fidelity import PRESETS, Fidelity, parse_fidelity
from sim.scenario import REWARD_SCHEMES, Cell, Rewards, Scenario, rewards_from_text

DEFAULT_EPISODES = 3000  # the paper's
MAX_EPISODES = 10_000_000
MAX_SEEDS = 10_000
MAX_SEED = 2**63 - 1
MAX_DRIVES = 100_000
MAX_JOBS = 4096

ScenarioLike = str | Path | Scenario
MethodLike = str | type


def err(fn: str, arg: str, problem: str, fix: str) -> InputError:
    return InputError(f"scenarios.api.{fn}", arg, problem, fix)


# ---------------------------------------------------------------- arguments, checked


def whole(fn: str, arg: str, value: Any, lo: int, hi: int, example: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise err(fn, arg, f"is {value!r}, not a whole number", f"pass e.g. {arg}={example}")
    if int(value) < lo:
        raise err(fn, arg, f"must be >= {lo}, got {value}", f"pass e.g. {arg}={example}")
    if int(value) > hi:
        raise err(fn, arg, f"is {value:,}, more than the limit {hi:,}",
                  f"pass at most {arg}={hi}")
    return int(value)


def scenario_arg(fn: str, scenario: Any) -> str | Scenario:
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, Path):
        return str(scenario)
    if isinstance(scenario, str) and scenario.strip():
        return scenario
    raise err(fn, "scenario", f"is {scenario!r}", "pass a built-in name (rnhql scenarios), "
               "a .toml or .map path, or a sim.scenario.Scenario")


def cell_arg(fn: str, arg: str, value: Any) -> Cell | None:
    if value is None:
        return None
    try:
        x, y = value
    except (TypeError, ValueError):
        raise err(fn, arg, f"is {value!r}, not a cell", f"pass {arg}=(x, y)") from None
    if not all(isinstance(v, int | np.integer) and not isinstance(v, bool) for v in (x, y)):
        raise err(fn, arg, f"is {value!r}: a cell's x and y are whole numbers",
                  f"pass {arg}=(x, y) with integers, e.g. {arg}=(3, 5)")
    return int(x), int(y)


def rewards_arg(fn: str, rewards: Any) -> str | None:
    """The reward scheme as a sweep holds it: text, or None for the scenario's own."""
    if rewards is None:
        return DEFAULT_REWARDS
    if isinstance(rewards, Rewards):
        return f"goal={rewards.goal!r},bump={rewards.bump!r},step={rewards.step!r}"
    if rewards == "scenario":
        return None
    if not isinstance(rewards, str):
        raise err(fn, "rewards", f"is a {type(rewards).__name__}", "pass a scheme name ("
                   f"{', '.join(REWARD_SCHEMES)}), 'scenario', 'goal=..,bump=..,step=..' or a "
                   "sim.scenario.Rewards")
    try:
        rewards_from_text(rewards)
    except InputError as exc:
        raise err(fn, "rewards", exc.problem, exc.fix.replace("--rewards ", "rewards=")) \
            from None
    return rewards


def fidelity_arg(fn: str, fidelity: Any, physics: bool) -> Fidelity | None:
    """The fidelity, parsed once and checked: what a sweep's specs hold, carried to the
    kernel as it is; None: the scenario's own."""
    if fidelity is None:
        return None
    if not physics:
        raise err(fn, "fidelity", f"{fidelity!r} applies to the physics world only",
                   "add world='physics' (worlds=('grid', 'physics')), or drop fidelity")
    if isinstance(fidelity, Fidelity):
        fidelity.validate(f"scenarios.api.{fn}: fidelity")
        return fidelity
    if not isinstance(fidelity, str):
        raise err(fn, "fidelity", f"is a {type(fidelity).__name__}", "pass a rung's name ("
                   f"{', '.join(PRESETS)}), 'PRESET,knob=value', or a Fidelity")
    return parse_fidelity(fidelity, f"scenarios.api.{fn}: fidelity")


def method_arg(fn: str, method: Any) -> str:
    """A method's name in a sweep: a registry name, or ``module:Class`` (a class given as an
    object is remembered in this process and the workers it forks)."""
    if isinstance(method, type):
        if issubclass(method, MethodConfig):
            name = method.cli if METHODS.get(method.cli) is method else located_name(method)
        else:
            try:
                name = remember(method)
            except ValueError as exc:
                raise err(fn, "method", str(exc), "see docs/python-api.md, your own "
                           "learner") from None
    elif isinstance(method, str) and method.strip():
        name = method.strip()
    else:
        raise err(fn, "method", f"is {method!r}", "pass a method's name (docs/methods.md), "
                   "'module:Class', or a learner class")
    try:
        method_class(name)
    except InputError as exc:
        raise err(fn, "method", exc.problem, exc.fix) from None
    return name


def methods_arg(fn: str, methods: Any) -> list[str]:
    if methods is None:
        return list(comparison_methods())
    if isinstance(methods, str | type):
        methods = [methods]
    names = [method_arg(fn, m) for m in methods]
    if not names:
        raise err(fn, "methods", "is empty", "pass e.g. methods=['rnh-ql+', 'haql']")
    twice = [m for i, m in enumerate(names) if m in names[:i]]
    if twice:
        raise err(fn, "methods", f"names {twice[0]!r} twice", "list each method once")
    return names


def worlds_arg(fn: str, worlds: Any) -> list[str]:
    if isinstance(worlds, str):
        worlds = [w.strip() for w in worlds.split(",")]
    worlds = list(worlds)
    bad = [w for w in worlds if w not in WORLDS]
    if not worlds or bad:
        raise err(fn, "worlds", f"has {bad[0]!r}" if bad else "is empty",
                   f"use {', '.join(WORLDS)}")
    if len(set(worlds)) != len(worlds):
        raise err(fn, "worlds", "names a world twice", "list each world once")
    return worlds


def settings_arg(fn: str, settings: Mapping[str, float] | None) -> tuple[tuple[str, float], ...]:
    if not settings:
        return ()
    if not isinstance(settings, Mapping):
        raise err(fn, "settings", f"is a {type(settings).__name__}",
                   "pass a dict of config fields, e.g. settings={'eps': 0.2}")
    out = []
    for k, v in settings.items():
        if isinstance(v, bool) or not isinstance(v, int | float | np.number):
            raise err(fn, f"settings[{k!r}]", f"is {v!r}, not a number",
                       f"pass e.g. settings={{{k!r}: 0.2}}")
        out.append((str(k), float(v)))
    return tuple(out)


def record_arg(fn: str, record: Any, name: str, rest: str) -> str | None:
    """``record``: True for the default path under recordings/, a .rrd path, or None."""
    if record is None or record is False:
        return None
    if record is True:
        safe = re.sub(r"[^A-Za-z0-9._-]+", "_", name).lstrip("._")[:100] or "run"
        path = Path(f"recordings/{safe}-{re.sub(r'[^A-Za-z0-9._+-]+', '_', rest)}.rrd")
    elif isinstance(record, str | Path) and str(record).strip():
        path = Path(record)
    else:
        raise err(fn, "record", f"is {record!r}", "pass True, or a path ending in .rrd")
    if path.suffix != ".rrd":
        raise err(fn, "record", f"{path} does not end in .rrd", "name it e.g. run.rrd")
    check_output(path, "record")
    refused = recording_refused()
    if refused is not None:
        raise err(fn, "record", *refused)
    folder = path.parent if str(path.parent) else Path(".")
    while not folder.exists() and folder != folder.parent:  # made when the run records
        folder = folder.parent
    if not os.access(folder, os.W_OK):  # now, not as a bare OSError after the training
        raise err(fn, "record", f"cannot write to {folder}/", "record elsewhere, or make "
                  "the folder writable")
    return str(path)


def init_arg(fn: str, init: Any, method: str, world: str, sc: Scenario, layout: str,
             n_states: int, geometry: Any, resume: Any) -> Any:
    """``init``: a :class:`~scenarios.values.Run` returned by :func:`scenarios.api.train`, or
    a saved agent (``.npz``), as the warm start of a physics run
    (:class:`scenarios.runs.warm.Carried`), checked against this run before any work."""
    if init is None:
        return None
    if world != "physics":
        raise err(fn, "init", "warm-starts a physics run (the grid's learner continued at a "
                  "rung)", "pass world='physics' (to continue a grid run: resume=AGENT.npz)")
    if resume is not None:
        raise err(fn, "init", "and resume both say where the learner starts",
                  "pass one of them")
    from scenarios.runs.warm import Carried, carried_of_checkpoint  # (values import api_args)
    from scenarios.values import Run

    if isinstance(init, Run):
        carried = init.carried
        if carried is None:
            raise err(fn, "init", "this Run carries no learner (it was read from a "
                      "results.json)", "pass a Run returned by api.train, or a saved agent "
                      "(train(..., save='agent.npz'))")
    elif isinstance(init, str | Path) and str(init).strip():
        carried = carried_of_checkpoint(Path(init), n_states, geometry)
    else:
        raise err(fn, "init", f"is {type(init).__name__}", "pass a Run returned by api.train, "
                  "or the path of a saved agent (.npz)")
    if not isinstance(carried, Carried):
        raise err(fn, "init", "carries no learner", "pass a Run returned by api.train")
    carried.check(method, layout, n_states, sc.rewards.label(), "init", f"scenarios.api.{fn}")
    return carried


def pretrain_arg(fn: str, pretrain: Any, worlds: Sequence[str]) -> int:
    """``pretrain``: ``("grid", episodes)`` (or ``"grid:300"``): every physics run of the sweep
    first trains that many episodes in the grid; 0 when None."""
    if pretrain is None:
        return 0
    if isinstance(pretrain, str):
        world, sep, n = pretrain.partition(":")
        if not sep:
            raise err(fn, "pretrain", f"is {pretrain!r}", "pass e.g. pretrain=('grid', 300)")
        try:
            pretrain = (world.strip(), int(n))
        except ValueError:
            raise err(fn, "pretrain", f"has episodes {n!r}, not a whole number",
                      "pass e.g. pretrain=('grid', 300)") from None
    if not (isinstance(pretrain, tuple | list) and len(pretrain) == 2):
        raise err(fn, "pretrain", f"is {pretrain!r}", "pass e.g. pretrain=('grid', 300)")
    world, episodes = pretrain
    if world != "grid":
        raise err(fn, "pretrain", f"names the world {world!r}", "pretrain in 'grid' (to start "
                  "from a lower rung, train there and pass the Run as api.train's init)")
    if "physics" not in worlds:
        raise err(fn, "pretrain", "applies to physics runs", "pass world='physics', or drop "
                  "pretrain=...")
    if isinstance(episodes, bool) or not isinstance(episodes, int | np.integer) or \
            not 1 <= int(episodes) <= MAX_EPISODES:
        raise err(fn, "pretrain", f"has {episodes!r} episodes, not a whole number in "
                  f"1..{MAX_EPISODES:,}", "pass e.g. pretrain=('grid', 300)")
    return int(episodes)


def carried_methods_arg(fn: str, arg: str, methods: Sequence[str]) -> None:
    """A warm start (``pretrain`` or ``init``) carries each run's own learner into its next
    world: an :class:`InputError` for a batched learner, whose one object learns for a whole
    batch of runs and cannot continue one of them."""
    for name in methods:
        cls = method_class(name)
        if getattr(cls, "learner", None) is not None and is_batched(cls.learner):
            raise err(fn, arg, f"does not apply: {name} is a batched learner (one object for "
                      "a batch of runs), and a warm start carries one run's learner",
                      f"train it from scratch at the rung (drop {arg}=...), or write it "
                      "as a plain learner of one run")


def problem_of(fn: str, scenario: str | Scenario, start: Cell | None, goal: Cell | None,
             rewards: str | None, s_starts: float | None, worlds: Sequence[str]):
    if s_starts is not None and not (isinstance(s_starts, int | float) and
                                     0.0 <= s_starts < 1.0):
        raise err(fn, "s_starts", f"must be in [0, 1), got {s_starts!r}",
                   "pass e.g. s_starts=0.1 (one episode in ten starts at S)")
    sc, model = load(scenario, start, goal, rewards, s_starts)
    physics_budget(sc, worlds)
    return sc, model


def output_arg(fn: str, arg: str, path: Any, suffix: str | None = None) -> Path:
    """A file the call writes at the end, checked before any work: a path whose folder
    exists and takes files, not a folder (the run is not lost to a bad name)."""
    if not isinstance(path, str | os.PathLike):
        raise err(fn, arg, f"is {path!r}, not a path", f"pass {arg}='agent.npz'")
    try:
        return check_output_file(Path(path), arg, suffix)
    except InputError as e:
        raise err(fn, arg, e.problem, e.fix) from None


def scenario_name(scenario: str | Scenario) -> str:
    return scenario if isinstance(scenario, str) else scenario.name


def policy_table(fn: str, policy: Any, n_states: int) -> np.ndarray:
    """int64[n_states] from an array or a function of the cell; errors name the cell."""
    if callable(policy) and not isinstance(policy, np.ndarray):
        out = np.empty(n_states, dtype=np.int64)
        for s in range(n_states):
            got = policy(s)
            # an integer, or an integer array of one (what SB3's predict gives); a float, a
            # text, a bool or several actions are refused, not coerced
            a = np.asarray(got).reshape(-1)[0] if np.ndim(got) and np.size(got) == 1 else got
            if isinstance(a, bool | np.bool_) or not isinstance(a, int | np.integer) or \
                    not 0 <= int(a) <= 3:
                raise err(fn, "policy", f"returned {got!r} for cell {s}, not an action",
                           "return an int: 0 (up), 1 (down), 2 (left) or 3 (right)")
            out[s] = int(a)
    else:
        try:
            out = np.asarray(policy)
        except Exception:  # a ragged list
            raise err(fn, "policy", "is not an array of actions",
                       f"pass an int array of {n_states} actions") from None
        if out.shape != (n_states,) or not np.issubdtype(out.dtype, np.integer):
            raise err(fn, "policy", f"has shape {out.shape} and dtype {out.dtype}",
                       f"pass an int array of {n_states} actions, one per cell (or a "
                       "function of the cell)")
        out = out.astype(np.int64)
    bad = np.flatnonzero((out < 0) | (out > 3))
    if bad.size:
        raise err(fn, "policy", f"gives {out[bad[0]]} in cell {bad[0]}, not an action",
                   "use 0 (up), 1 (down), 2 (left) or 3 (right)")
    return out

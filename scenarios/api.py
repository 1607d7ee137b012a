"""rnhql as a library: scenario scripts train, compare and grade in Python and get typed
values back. The ``rnhql`` command is a shell over these calls.

- :func:`train`: one method (or a learner of your own) on one scenario, one seed -> :class:`Run`
- :func:`compare`: methods x seeds (x worlds) -> :class:`Comparison`
- :func:`grade`: any policy (an action per cell, or a function of the cell) driven from S at
  a fidelity, as the tool grades its own final policies -> :class:`Grade`
- :func:`optimum`: the yardsticks of a scenario at a fidelity (V* where defined) -> :class:`Optimum`

``scenario`` is a built-in name, a ``.toml``/``.map`` path or a :class:`sim.scenario.Scenario`;
a method is a registry name (``"rnh-ql+"``), ``"module:Class"``, or the class itself: a
plain-Python learner (:mod:`learning.plain`) or a compiled method's config. Bad input
raises :class:`sim.errors.InputError` naming the argument and the fix, before any work.
The same inputs give the same records as the command (tested). These names and their
keywords are kept stable.

>>> from scenarios import api                                              # doctest: +SKIP
>>> cmp = api.compare("paper-40", ["rnh-ql+", "st-ql"], seeds=3, episodes=300)  # doctest: +SKIP
>>> print(cmp.summary())                                                   # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from scenarios.runs.spec import WORLDS, ExperimentError, RunSpec, load
from scenarios.values import Comparison, Grade, Optimum, Run
from sim.errors import InputError
from sim.scenario import REWARD_SCHEMES, Cell, Rewards, Scenario

__all__ = ["Comparison", "Grade", "InputError", "Optimum", "Run", "compare", "grade",
           "optimum", "route", "train"]

DEFAULT_EPISODES = 3000  # the paper's
DEFAULT_REWARDS = "goal-only"  # as the command: the paper's own is rewards="paper"
MAX_EPISODES = 10_000_000
MAX_SEEDS = 10_000
MAX_SEED = 2**63 - 1
MAX_DRIVES = 100_000
MAX_JOBS = 4096

ScenarioLike = str | Path | Scenario
MethodLike = str | type


def _err(fn: str, arg: str, problem: str, fix: str) -> InputError:
    return InputError(f"scenarios.api.{fn}", arg, problem, fix)


# ---------------------------------------------------------------- arguments, checked


def _whole(fn: str, arg: str, value: Any, lo: int, hi: int, example: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise _err(fn, arg, f"is {value!r}, not a whole number", f"pass e.g. {arg}={example}")
    if not lo <= int(value) <= hi:
        raise _err(fn, arg, f"is {value}, outside {lo}..{hi:,}", f"pass e.g. {arg}={example}")
    return int(value)


def _scenario(fn: str, scenario: Any) -> str | Scenario:
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, Path):
        return str(scenario)
    if isinstance(scenario, str) and scenario.strip():
        return scenario
    raise _err(fn, "scenario", f"is {scenario!r}", "pass a built-in name (rnhql scenarios), "
               "a .toml or .map path, or a sim.scenario.Scenario")


def _cell(fn: str, arg: str, value: Any) -> Cell | None:
    if value is None:
        return None
    try:
        x, y = (int(v) for v in value)
    except (TypeError, ValueError):
        raise _err(fn, arg, f"is {value!r}, not a cell", f"pass {arg}=(x, y)") from None
    return x, y


def _rewards(fn: str, rewards: Any) -> str | None:
    """The reward scheme as a sweep holds it: text, or None for the scenario's own."""
    from sim.scenario import rewards_from_text

    if rewards is None:
        return DEFAULT_REWARDS
    if isinstance(rewards, Rewards):
        return f"goal={rewards.goal!r},bump={rewards.bump!r},step={rewards.step!r}"
    if rewards == "scenario":
        return None
    if not isinstance(rewards, str):
        raise _err(fn, "rewards", f"is a {type(rewards).__name__}", "pass a scheme name ("
                   f"{', '.join(REWARD_SCHEMES)}), 'scenario', 'goal=..,bump=..,step=..' or a "
                   "sim.scenario.Rewards")
    try:
        rewards_from_text(rewards)
    except InputError as exc:
        raise _err(fn, "rewards", exc.problem, exc.fix.replace("--rewards ", "rewards=")) \
            from None
    return rewards


def _fidelity(fn: str, fidelity: Any, physics: bool) -> str | None:
    """The fidelity as text (what a sweep's specs hold), checked; None: the scenario's own."""
    from sim.physics.fidelity import PRESETS, Fidelity, parse_fidelity

    if fidelity is None:
        return None
    if not physics:
        raise _err(fn, "fidelity", f"{fidelity!r} applies to the physics world only",
                   "add world='physics' (worlds=('grid', 'physics')), or drop fidelity")
    if isinstance(fidelity, Fidelity):
        fidelity.validate(f"scenarios.api.{fn}: fidelity")
        if PRESETS.get(fidelity.name) == fidelity:
            return fidelity.name
        exact = Fidelity()
        return ",".join(f"{f.name}={getattr(fidelity, f.name)}"
                        for f in dataclasses.fields(Fidelity)
                        if f.name != "name" and getattr(fidelity, f.name) != getattr(exact,
                                                                                     f.name)) \
            or "exact"
    if not isinstance(fidelity, str):
        raise _err(fn, "fidelity", f"is a {type(fidelity).__name__}", "pass a rung's name ("
                   f"{', '.join(PRESETS)}), 'PRESET,knob=value', or a Fidelity")
    try:
        parse_fidelity(fidelity, f"scenarios.api.{fn}: fidelity")
    except InputError:
        raise
    return fidelity


def _method(fn: str, method: Any) -> str:
    """A method's name in a sweep: a registry name, or ``module:Class`` (a class given as an
    object is remembered in this process and the workers it forks)."""
    from learning.config import MethodConfig
    from learning.plain import remember
    from scenarios.runs.spec import method_class

    if isinstance(method, type):
        if issubclass(method, MethodConfig):
            from learning.plain import located_name
            from learning.registry import METHODS

            name = method.cli if METHODS.get(method.cli) is method else located_name(method)
        else:
            try:
                name = remember(method)
            except ValueError as exc:
                raise _err(fn, "method", str(exc), "see docs/python-api.md, your own "
                           "learner") from None
    elif isinstance(method, str) and method.strip():
        name = method.strip()
    else:
        raise _err(fn, "method", f"is {method!r}", "pass a method's name (docs/methods.md), "
                   "'module:Class', or a learner class")
    try:
        method_class(name)
    except InputError as exc:
        raise _err(fn, "method", exc.problem, exc.fix) from None
    return name


def _methods(fn: str, methods: Any) -> list[str]:
    from learning.registry import comparison_methods

    if methods is None:
        return list(comparison_methods())
    if isinstance(methods, str | type):
        methods = [methods]
    names = [_method(fn, m) for m in methods]
    if not names:
        raise _err(fn, "methods", "is empty", "pass e.g. methods=['rnh-ql+', 'haql']")
    twice = [m for i, m in enumerate(names) if m in names[:i]]
    if twice:
        raise _err(fn, "methods", f"names {twice[0]!r} twice", "list each method once")
    return names


def _worlds(fn: str, worlds: Any) -> list[str]:
    if isinstance(worlds, str):
        worlds = [w.strip() for w in worlds.split(",")]
    worlds = list(worlds)
    bad = [w for w in worlds if w not in WORLDS]
    if not worlds or bad:
        raise _err(fn, "worlds", f"has {bad[0]!r}" if bad else "is empty",
                   f"use {', '.join(WORLDS)}")
    if len(set(worlds)) != len(worlds):
        raise _err(fn, "worlds", "names a world twice", "list each world once")
    return worlds


def _settings(fn: str, settings: Mapping[str, float] | None) -> tuple[tuple[str, float], ...]:
    if not settings:
        return ()
    if not isinstance(settings, Mapping):
        raise _err(fn, "settings", f"is a {type(settings).__name__}",
                   "pass a dict of config fields, e.g. settings={'eps': 0.2}")
    out = []
    for k, v in settings.items():
        if isinstance(v, bool) or not isinstance(v, int | float | np.number):
            raise _err(fn, f"settings[{k!r}]", f"is {v!r}, not a number",
                       f"pass e.g. settings={{{k!r}: 0.2}}")
        out.append((str(k), float(v)))
    return tuple(out)


def _record(fn: str, record: Any, name: str, rest: str) -> str | None:
    """``record``: True for the default path under recordings/, a .rrd path, or None."""
    import re

    from sim.files import check_output

    if record is None or record is False:
        return None
    if record is True:
        safe = re.sub(r"[^A-Za-z0-9._-]+", "_", name).lstrip("._")[:100] or "run"
        path = Path(f"recordings/{safe}-{re.sub(r'[^A-Za-z0-9._+-]+', '_', rest)}.rrd")
    elif isinstance(record, str | Path) and str(record).strip():
        path = Path(record)
    else:
        raise _err(fn, "record", f"is {record!r}", "pass True, or a path ending in .rrd")
    if path.suffix != ".rrd":
        raise _err(fn, "record", f"{path} does not end in .rrd", "name it e.g. run.rrd")
    check_output(path, "record")
    return str(path)


def _problem(fn: str, scenario: str | Scenario, start: Cell | None, goal: Cell | None,
             rewards: str | None, s_starts: float | None, worlds: Sequence[str]):
    from scenarios.runs.spec import physics_budget

    if s_starts is not None and not (isinstance(s_starts, int | float) and
                                     0.0 <= s_starts < 1.0):
        raise _err(fn, "s_starts", f"must be in [0, 1), got {s_starts!r}",
                   "pass e.g. s_starts=0.1 (one episode in ten starts at S)")
    sc, model = load(scenario, start, goal, rewards, s_starts)
    physics_budget(sc, worlds)
    return sc, model


def _scenario_name(scenario: str | Scenario) -> str:
    return scenario if isinstance(scenario, str) else scenario.name


# ---------------------------------------------------------------- train


def train(scenario: ScenarioLike, method: MethodLike = "rnh-ql+", *, world: str = "grid",
          fidelity: Any = None, episodes: int | None = None, seed: int = 0,
          rewards: Any = None, record: str | Path | bool | None = None,
          settings: Mapping[str, float] | None = None, s_starts: float | None = None,
          start: Cell | None = None, goal: Cell | None = None,
          save: str | Path | None = None, resume: str | Path | None = None,
          record_every: int = 10, record_values_every: int = 300) -> Run:
    """One method on one scenario, one seed: the run ``rnhql train`` makes.

    ``world``: ``"grid"`` or ``"physics"`` (``fidelity``: a rung such as ``"noisy"``, a
    ``Fidelity``, default the scenario's own); ``episodes``: default 3000; ``rewards``:
    ``None`` for goal-only (as the command), ``"paper"``, ``"scenario"`` (the scenario's
    own), text or a ``Rewards``; ``settings``: the method's config fields, e.g.
    ``{"eps": 0.2}``; ``record``: ``True`` or a ``.rrd`` path; ``save``/``resume``: an
    ``AGENT.npz`` checkpoint of a compiled method's grid run.
    """
    fn = "train"
    scenario = _scenario(fn, scenario)
    name = _method(fn, method)
    if world not in WORLDS:
        raise _err(fn, "world", f"is {world!r}", f"use one of: {', '.join(WORLDS)}")
    episodes = _whole(fn, "episodes", DEFAULT_EPISODES if episodes is None else episodes, 1,
                      MAX_EPISODES, 300)
    seed = _whole(fn, "seed", seed, 0, MAX_SEED, 0)
    rewards_text = _rewards(fn, rewards)
    fid_text = _fidelity(fn, fidelity, world == "physics")
    overrides = _settings(fn, settings)
    start, goal = _cell(fn, "start", start), _cell(fn, "goal", goal)
    record_every = _whole(fn, "record_every", record_every, 1, MAX_EPISODES, 10)
    record_values_every = _whole(fn, "record_values_every", record_values_every, 1,
                                 MAX_EPISODES, 300)
    sc, model = _problem(fn, scenario, start, goal, rewards_text, s_starts, [world])
    from scenarios.runs.single import train_single

    rec_path = _record(fn, record, sc.name, f"{name.replace(':', '.')}-{world}-s{seed}")
    spec = RunSpec(scenario, name, seed, episodes, world, overrides, start=start, goal=goal,
                   rewards=rewards_text, fidelity=fid_text, s_starts=s_starts)
    rec = train_single(spec, sc, model, save=save, resume=resume, record=rec_path,
                       record_every=record_every, record_values_every=record_values_every)
    return Run.from_record(rec, None if rec_path is None else Path(rec_path))


# ---------------------------------------------------------------- compare


def compare(scenario: ScenarioLike, methods: Sequence[MethodLike] | MethodLike | None = None,
            *, worlds: Sequence[str] | str = ("grid",), fidelity: Any = None, seeds: int = 10,
            episodes: int | None = None, rewards: Any = None, jobs: int | None = None,
            out: str | Path | None = None, record: str | Path | bool | None = None,
            settings: Mapping[str, float] | None = None, seed_base: int = 0,
            resume: bool = False, backend: str = "local", address: str | None = None,
            s_starts: float | None = None, start: Cell | None = None,
            goal: Cell | None = None, record_every: int = 100, record_values_every: int = 300,
            record_seeds: int = 1, figures: bool = True, progress: bool = False,
            start_method: str | None = None) -> Comparison:
    """Methods x seeds (x worlds) on one scenario: the sweep ``rnhql compare`` runs.

    ``methods``: names, ``"module:Class"`` or classes (default: the comparison's list);
    ``seeds``: how many, from ``seed_base``; ``jobs``: worker processes (default every
    core); ``out``: a folder for ``results.json``, ``summary.md`` and figures (``None``:
    nothing is written, :meth:`Comparison.save` writes them later); ``resume``: skip runs
    finished in ``out``; ``settings``: config fields for every method that has them;
    ``backend``: ``"local"`` or ``"ray"`` (``address``); ``progress``: a progress line on
    stderr; ``start_method``: the worker pool's (``"fork"``, ``"spawn"``,
    ``"forkserver"``; default Python's). The rest as :func:`train`.
    """
    fn = "compare"
    scenario = _scenario(fn, scenario)
    names = _methods(fn, methods)
    worlds = _worlds(fn, worlds)
    n_seeds = _whole(fn, "seeds", seeds, 1, MAX_SEEDS, 10)
    seed_base = _whole(fn, "seed_base", seed_base, 0, MAX_SEED - n_seeds + 1, 0)
    episodes = _whole(fn, "episodes", DEFAULT_EPISODES if episodes is None else episodes, 1,
                      MAX_EPISODES, 300)
    rewards_text = _rewards(fn, rewards)
    fid_text = _fidelity(fn, fidelity, "physics" in worlds)
    overrides = _settings(fn, settings)
    start, goal = _cell(fn, "start", start), _cell(fn, "goal", goal)
    if jobs is not None:
        jobs = _whole(fn, "jobs", jobs, 1, MAX_JOBS, 2)
    if resume and out is None:
        raise _err(fn, "resume", "needs out: the folder whose finished runs to keep",
                   "pass out='DIR' as well, or drop resume")
    sc, _ = _problem(fn, scenario, start, goal, rewards_text, s_starts, worlds)
    per_method = settings_per_method(names, overrides)
    from scenarios.experiments.compare import SweepRecording, assemble, make_specs, run_sweep
    from scenarios.runs.backends import Progress

    specs = make_specs(scenario, names, list(range(seed_base, seed_base + n_seeds)), episodes,
                       worlds, per_method, start=start, goal=goal, rewards=rewards_text,
                       fidelity=fid_text, s_starts=s_starts)
    execute, kwargs = _backend(fn, backend, address, jobs, start_method)
    rec_path = _record(fn, record, _scenario_name(scenario).rsplit("/", 1)[-1]
                       .removesuffix(".toml"), "compare")
    recording = None
    if rec_path is not None:
        recording = SweepRecording(
            rec_path, every=_whole(fn, "record_every", record_every, 1, MAX_EPISODES, 100),
            values_every=_whole(fn, "record_values_every", record_values_every, 1,
                                MAX_EPISODES, 300),
            detail_seeds=_whole(fn, "record_seeds", record_seeds, 1, MAX_SEEDS, 1))
    bar = Progress(len(specs), enabled=bool(progress))
    if out is None and recording is None:
        try:
            records = execute(specs, progress=bar, **kwargs)
        finally:
            bar.close()
        results = assemble(specs, records)
    else:
        with _out_dir(out) as out_dir:
            results = run_sweep(specs, out_dir, execute, resume=resume, recording=recording,
                                progress=bar, figures=figures and out is not None, **kwargs)
    rec = None if rec_path is None else Path(rec_path)
    return Comparison(sc, [Run.from_record(r, rec) for r in results["runs"]], results,
                      None if out is None else Path(out), rec)


def settings_per_method(methods: Sequence[str], overrides: tuple[tuple[str, float], ...]
                        ) -> dict[str, tuple[tuple[str, float], ...]]:
    """``settings`` (``--set``) for every method that has the field; an error only when none
    has it. Every method's config is built here once, so a bad value fails before any run."""
    from scenarios.runs.spec import make_config, method_class, settable_fields

    out: dict[str, tuple[tuple[str, float], ...]] = {}
    for m in methods:
        make_config(m, ())
        fields = set(settable_fields(method_class(m)))
        out[m] = tuple((k, v) for k, v in overrides if k in fields)
        make_config(m, out[m])
    for k, _ in overrides:
        if not any(k in dict(o) for o in out.values()):
            raise ExperimentError("command line", f"--set {k}",
                                  f"none of the methods ({', '.join(methods)}) has a field "
                                  f"{k!r}", "use one of their fields: " + ", ".join(sorted(
                                      {f for m in methods
                                       for f in settable_fields(method_class(m))})))
    return out


def _backend(fn: str, backend: str, address: str | None, jobs: int | None,
             start_method: str | None) -> tuple[Callable[..., Any], dict[str, Any]]:
    from scenarios.runs.backends import run_local, run_ray

    if backend == "local":
        if address is not None:
            raise _err(fn, "address", "only applies with backend='ray'",
                       "pass backend='ray', or drop address")
        if start_method not in (None, "fork", "spawn", "forkserver"):
            raise _err(fn, "start_method", f"is {start_method!r}",
                       "use 'fork', 'spawn' or 'forkserver' (or None)")
        return run_local, {"jobs": jobs or os.cpu_count() or 1, "start_method": start_method}
    if backend == "ray":
        return run_ray, {"address": address, "num_cpus": jobs}
    raise _err(fn, "backend", f"is {backend!r}", "use 'local' or 'ray'")


@contextlib.contextmanager
def _out_dir(out: str | Path | None) -> Iterator[Path]:
    """``out``, or a folder that is gone afterwards (a recorded sweep with nothing to keep)."""
    if out is not None:
        yield Path(out)
        return
    with tempfile.TemporaryDirectory(prefix="rnhql-sweep-") as tmp:
        yield Path(tmp)


# ---------------------------------------------------------------- grade, optimum


def optimum(scenario: ScenarioLike, *, fidelity: Any = "exact", rewards: Any = None,
            start: Cell | None = None, goal: Cell | None = None) -> Optimum:
    """The yardsticks at ``fidelity``: the grid's BFS optimum, the physics world's at exact,
    V*(S) (expected primitives) and P(G) where V* is defined (not where the state is
    hidden: open loop, localisation), and the disc's continuous path. V* is built by
    driving and cached on disk (``rnhql optimum`` says what it cost)."""
    fn = "optimum"
    scenario = _scenario(fn, scenario)
    fid_text = _fidelity(fn, fidelity, True) or "exact"
    sc, model = _problem(fn, scenario, _cell(fn, "start", start), _cell(fn, "goal", goal),
                         _rewards(fn, rewards), None, ["physics"])
    return _optimum(sc, model, fid_text)


def _optimum(sc: Scenario, model: Any, fid_text: str) -> Optimum:
    from scenarios.experiments.compare import optimum_at_fidelity
    from sim.physics.fidelity import parse_fidelity
    from sim.physics.model import physics_model
    from sim.physics.optimum import continuous_optimum_m

    fid = parse_fidelity(fid_text)
    exact = physics_model(sc).optimal_route_length
    if fid.is_exact:
        v, p = (float(exact), 1.0) if exact >= 0 else (float("inf"), 0.0)
    else:
        with _optimum_always():
            at = optimum_at_fidelity(sc, fid)
        v, p = (None, None) if at is None else (at["expected_primitives"],
                                                at["p_goal_within_budget"])
    cont = continuous_optimum_m(sc)
    return Optimum(fid.label, int(model.optimal_route_length), int(exact), v, p,
                   int(sc.steps_per_episode), None if cont is None else round(cont, 4))


@contextlib.contextmanager
def _optimum_always() -> Iterator[None]:
    """V* even where a test sweep switched it off for its sweeps (RNHQL_NO_OPTIMUM)."""
    old = os.environ.pop("RNHQL_NO_OPTIMUM", None)
    try:
        yield
    finally:
        if old is not None:
            os.environ["RNHQL_NO_OPTIMUM"] = old


def grade(policy: np.ndarray | Sequence[int] | Callable[[int], int], scenario: ScenarioLike,
          *, fidelity: Any = "exact", drives: int = 50, seed: int = 0, rewards: Any = None,
          start: Cell | None = None, goal: Cell | None = None,
          with_optimum: bool = True) -> Grade:
    """Drive ``policy`` from S at ``fidelity``, each drive with its own noise stream, exactly
    as the tool grades its own final policies (:mod:`scenarios.runs.physics_grading`): a
    run's final grade is ``grade(run.policy, ..., seed=run.seed)``.

    ``policy``: an action per cell (``int[n_states]``, state = ``iy * nx + ix``) or a
    function of the cell returning an action (e.g. ``lambda s: int(model.predict(s,
    deterministic=True)[0])`` for a Stable-Baselines3 model), called once per cell.
    ``drives``: above ``exact`` (at ``exact`` every drive is the same, so it drives once).
    ``with_optimum``: also build V* (cached on disk) and say whether the policy matches it.
    """
    fn = "grade"
    scenario = _scenario(fn, scenario)
    fid_text = _fidelity(fn, fidelity, True) or "exact"
    drives = _whole(fn, "drives", drives, 1, MAX_DRIVES, 50)
    seed = _whole(fn, "seed", seed, 0, MAX_SEED, 0)
    sc, model = _problem(fn, scenario, _cell(fn, "start", start), _cell(fn, "goal", goal),
                         _rewards(fn, rewards), None, ["physics"])
    table = policy_table(fn, policy, model.n_states)
    from learning.policy_state import policy_state
    from learning.train import greedy_test
    from scenarios.experiments.compare import matches_optimum
    from scenarios.runs.physics_grading import FINAL_TAG, Grader
    from sim.physics.fidelity import parse_fidelity

    fid = parse_fidelity(fid_text)
    grader = Grader(sc, fid)
    st = policy_state(table)
    n = 1 if fid.is_exact else drives
    r = grader.drive(st, n, seed if not fid.is_exact else 0, FINAL_TAG if not fid.is_exact
                     else 0, measure_metres=True, keep_routes=True, keep_path=True)
    summary = r.summary()
    walk, _ = greedy_test(st, model)
    opt = _optimum(sc, model, fid_text) if with_optimum else None
    optimal = None
    if opt is not None and opt.expected_primitives is not None:
        if fid.is_exact:
            optimal = bool(r.reached[0]) and int(r.primitives[0]) == opt.physics_route_length
        else:
            from scenarios.experiments.compare import optimum_at_fidelity

            with _optimum_always():
                at = optimum_at_fidelity(sc, fid)
            optimal = None if at is None else matches_optimum(summary, at)
    med = summary["primitives_median"]
    return Grade(fid.label, r.n, seed, float(summary["p_goal"]),
                 tuple(summary["p_goal_ci95"]),
                 summary["primitives_mean"], None if med is None else float(med),
                 float(r.contacts.mean()), None if walk < 0 else int(walk), opt, optimal,
                 dict(summary))


def policy_table(fn: str, policy: Any, n_states: int) -> np.ndarray:
    """int64[n_states] from an array or a function of the cell; errors name the cell."""
    if callable(policy) and not isinstance(policy, np.ndarray):
        out = np.empty(n_states, dtype=np.int64)
        for s in range(n_states):
            a = policy(s)
            a = np.asarray(a).reshape(-1)[0] if np.ndim(a) else a
            try:
                out[s] = int(a)
            except (TypeError, ValueError):
                raise _err(fn, "policy", f"returned {a!r} for cell {s}, not an action",
                           "return 0 (up), 1 (down), 2 (left) or 3 (right)") from None
    else:
        try:
            out = np.asarray(policy)
        except Exception:  # a ragged list
            raise _err(fn, "policy", "is not an array of actions",
                       f"pass an int array of {n_states} actions") from None
        if out.shape != (n_states,) or not np.issubdtype(out.dtype, np.integer):
            raise _err(fn, "policy", f"has shape {out.shape} and dtype {out.dtype}",
                       f"pass an int array of {n_states} actions, one per cell (or a "
                       "function of the cell)")
        out = out.astype(np.int64)
    bad = np.flatnonzero((out < 0) | (out > 3))
    if bad.size:
        raise _err(fn, "policy", f"gives {out[bad[0]]} in cell {bad[0]}, not an action",
                   "use 0 (up), 1 (down), 2 (left) or 3 (right)")
    return out


def route(agent: str | Path, scenario: ScenarioLike, *, fidelity: Any = "exact",
          rewards: Any = None, drives: int = 50, seed: int = 0) -> Grade:
    """A saved agent (``train(..., save=...)``, ``rnhql train --save``) graded from S: its
    greedy policy through :func:`grade`."""
    from learning.checkpoint import load_checkpoint
    from learning.geometry import geometry_of
    from learning.readout import greedy_actions

    scenario = _scenario("route", scenario)
    _, model = _problem("route", scenario, None, None, _rewards("route", rewards), None,
                         ["physics"])
    ck = load_checkpoint(agent, None, model.n_states, geometry_of(model))
    from scenarios.runs.spec import layout_digest

    ck.check_problem({"layout": layout_digest(scenario)})  # trained on this layout
    return grade(greedy_actions(ck.state), scenario, fidelity=fidelity, drives=drives,
                 seed=seed, rewards=rewards)

"""rnhql as a library: scenario scripts train, compare and grade in Python and get typed
values back. The ``rnhql`` command is a shell over these calls.

- :func:`train`: one method (or a learner of your own) on one scenario, one seed -> :class:`Run`
- :func:`compare`: methods x seeds (x worlds) -> :class:`Comparison`
- :func:`grade`: any policy (an action per cell, or a function of the cell) driven from S at
  a fidelity, as the tool grades its own final policies -> :class:`Grade`
- :func:`optimum`: the yardsticks of a scenario at a fidelity (V* where defined) -> :class:`Optimum`
- :func:`route`: a saved agent's greedy policy graded from S -> :class:`Grade`
- :func:`aliasing`: how many next cells a (cell, action) leads to at a fidelity -> :class:`Aliasing`
- :func:`crosscheck`: the same primitives in IR-SIM, an independent simulator -> :class:`Crosscheck`

``scenario`` is a built-in name, a ``.toml``/``.map`` path or a :class:`sim.scenario.Scenario`;
a method is a registry name (``"rnh-ql+"``), ``"module:Class"``, or the class itself: a
plain-Python learner (:mod:`learning.plain.learner`) or a compiled method's config. Bad input
raises :class:`sim.errors.InputError` naming the argument and the fix, before any work.
The same inputs give the same records as the command (tested). These names and their
keywords are kept stable.

>>> from scenarios import api                                              # doctest: +SKIP
>>> cmp = api.compare("paper-40", ["rnh-ql+", "st-ql"], seeds=3, episodes=300)  # doctest: +SKIP
>>> print(cmp.summary())                                                   # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from learning.compiled.readout import greedy_actions
from learning.drivers.checkpoint import load_checkpoint
from learning.drivers.train import greedy_test
from learning.geometry import geometry_of
from learning.plain.learner import is_plain
from learning.plain.policy import policy_state
from scenarios.api_args import (
    DEFAULT_EPISODES,
    MAX_DRIVES,
    MAX_EPISODES,
    MAX_JOBS,
    MAX_SEED,
    MAX_SEEDS,
    MethodLike,
    ScenarioLike,
    carried_methods_arg,
    cell_arg,
    err,
    fidelity_arg,
    init_arg,
    method_arg,
    methods_arg,
    output_arg,
    policy_table,
    pretrain_arg,
    problem_of,
    record_arg,
    rewards_arg,
    scenario_arg,
    scenario_name,
    settings_arg,
    whole,
    worlds_arg,
)
from scenarios.api_models import _optimum_always, aliasing, crosscheck, optimum, optimum_of
from scenarios.runs.physics_grading import FINAL_TAG, Grader
from scenarios.runs.single import train_single
from scenarios.runs.spec import (
    WORLDS,
    ExperimentError,
    RunSpec,
    layout_digest,
    make_config,
    method_class,
    settable_fields,
)
from scenarios.sweep.execute import BACKENDS, START_METHODS, sweep
from scenarios.sweep.run import (
    SweepRecording,
    make_specs,
    matches_optimum,
    optimum_at_fidelity,
)
from scenarios.values import (
    Aliasing,
    Comparison,
    Crosscheck,
    Grade,
    Optimum,
    Route,
    Run,
    TrainPlan,
)
from sim.errors import InputError
from sim.grid.planning import bfs_route
from sim.physics.fidelity import Fidelity, parse_fidelity
from sim.scenario import Cell, Scenario

__all__ = ["Aliasing", "Comparison", "Crosscheck", "Grade", "InputError", "Optimum", "Route",
           "Run", "TrainPlan", "aliasing", "compare", "crosscheck", "grade", "optimum", "route",
           "train"]

# ---------------------------------------------------------------- train


def train(scenario: ScenarioLike, method: MethodLike = "rnh-ql+", *, world: str = "grid",
          fidelity: Any = None, episodes: int | None = None, seed: int = 0,
          rewards: Any = None, record: str | Path | bool | None = None,
          settings: Mapping[str, float] | None = None, s_starts: float | None = None,
          start: Cell | None = None, goal: Cell | None = None,
          save: str | Path | None = None, resume: str | Path | None = None,
          record_every: int = 10, record_values_every: int = 300,
          init: Run | str | Path | None = None, pretrain: Any = None,
          announce: Callable[[TrainPlan], None] | None = None) -> Run:
    """One method on one scenario, one seed: the run ``rnhql train`` makes.

    ``world``: ``"grid"`` or ``"physics"`` (``fidelity``: a rung such as ``"noisy"``, a
    ``Fidelity``, default the scenario's own); ``episodes``: default 3000; ``rewards``:
    ``None`` for goal-only (as the command), ``"paper"``, ``"scenario"`` (the scenario's
    own), text or a ``Rewards``; ``settings``: the method's config fields, e.g.
    ``{"eps": 0.2}``; ``record``: ``True`` or a ``.rrd`` path; ``save``/``resume``: an
    ``AGENT.npz`` checkpoint of a compiled method's grid run.

    Learn on the grid, finish on the robot: ``init`` (a physics run) starts from a learner
    trained in another world, a :class:`Run` this function returned (any method, plain
    learners too) or a saved agent; its learner and start streams continue, so
    ``train(..., seed=s)`` in the grid then ``train(..., world="physics", init=that,
    seed=s)`` is the run ``compare(..., pretrain=("grid", n))`` makes for seed ``s``.
    ``pretrain=("grid", n)`` does both phases in one call. The record's ``pretrain`` entry
    counts the first phase in its own currency and grades its policy at this run's rung.
    ``announce``: called once every argument is checked (and a checkpoint to resume
    loaded), before any training, with a :class:`TrainPlan`.
    """
    fn = "train"
    scenario = scenario_arg(fn, scenario)
    name = method_arg(fn, method)
    if world not in WORLDS:
        raise err(fn, "world", f"is {world!r}, not a world", f"use one of: {', '.join(WORLDS)}")
    episodes = whole(fn, "episodes", DEFAULT_EPISODES if episodes is None else episodes, 1,
                      MAX_EPISODES, 300)
    seed = whole(fn, "seed", seed, 0, MAX_SEED, 0)
    rewards_text = rewards_arg(fn, rewards)
    fid = fidelity_arg(fn, fidelity, world == "physics")
    overrides = settings_arg(fn, settings)
    start, goal = cell_arg(fn, "start", start), cell_arg(fn, "goal", goal)
    record_every = whole(fn, "record_every", record_every, 1, MAX_EPISODES, 10)
    record_values_every = whole(fn, "record_values_every", record_values_every, 1,
                                 MAX_EPISODES, 300)
    sc, model = problem_of(fn, scenario, start, goal, rewards_text, s_starts, [world])
    n_pre = pretrain_arg(fn, pretrain, [world])
    carried = init_arg(fn, init, name, world, sc, layout_digest(scenario, start, goal),
                       int(model.n_states), geometry_of(model), resume)
    if carried is not None and n_pre:
        raise err(fn, "pretrain", "and init both say where the learner starts",
                  "pass one of them")
    if n_pre or carried is not None:
        carried_methods_arg(fn, "pretrain" if n_pre else "init", [name])
    cfg = make_config(name, overrides)  # a bad setting fails here, before any work
    if is_plain(cfg) and (save is not None or resume is not None):
        raise err(fn, "save" if save is not None else "resume",
                  f"does not apply: {name} is a plain-Python learner, its state is its own",
                  "save it from your own code (the returned Run has its policy), or drop "
                  + ("save=..." if save is not None else "resume=..."))
    if resume is not None and world != "grid":
        raise err(fn, "resume", "is only supported for grid runs",
                  "drop resume=... or pass world='grid'")
    if save is not None:  # checked now: not after training, with the run lost
        output_arg(fn, "save", save)

    rec_path = record_arg(fn, record, sc.name, f"{name.replace(':', '.')}-{world}-s{seed}")
    spec = RunSpec(scenario, name, seed, episodes, world, overrides, start=start, goal=goal,
                   rewards=rewards_text, fidelity=fid, s_starts=s_starts, pretrain=n_pre)

    def said(resumed: int | None) -> None:
        if announce is not None:
            announce(TrainPlan(cfg.name, sc, world, spec.fidelity_spec.label
                               if world == "physics" else None, seed, episodes, resumed,
                               n_pre))

    rec, out = train_single(spec, sc, model, save=save, resume=resume, record=rec_path,
                            record_every=record_every, record_values_every=record_values_every,
                            init=carried, announce=said)
    return dataclasses.replace(Run.from_record(rec, None if rec_path is None
                                               else Path(rec_path)), carried=out)


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
            start_method: str | None = None, pretrain: Any = None,
            announce: Callable[[int, list[str], list[str]], None] | None = None) -> Comparison:
    """Methods x seeds (x worlds) on one scenario: the sweep ``rnhql compare`` runs.

    ``methods``: names, ``"module:Class"`` or classes (default: the comparison's list);
    ``seeds``: how many, from ``seed_base``; ``jobs``: worker processes (default every
    core); ``out``: a folder for ``results.json``, ``summary.md`` and figures (``None``:
    nothing is written, :meth:`Comparison.save` writes them later); ``resume``: skip runs
    finished in ``out``; ``settings``: config fields for every method that has them;
    ``backend``: ``"local"`` or ``"ray"`` (``address``); ``progress``: a progress line on
    stderr; ``start_method``: the worker pool's (``"fork"``, ``"spawn"``,
    ``"forkserver"``; default Python's); ``pretrain``: ``("grid", n)``: every physics run
    first trains ``n`` episodes in the grid on its own streams, then ``episodes`` at the
    rung (common random numbers: the same grid phase as a grid run of that seed);
    ``announce``: called once every argument is checked, before any run, with (runs,
    methods, worlds) (the command prints its first lines there). The rest as :func:`train`.
    """
    fn = "compare"
    scenario = scenario_arg(fn, scenario)
    names = methods_arg(fn, methods)
    worlds = worlds_arg(fn, worlds)
    n_seeds = whole(fn, "seeds", seeds, 1, MAX_SEEDS, 10)
    seed_base = whole(fn, "seed_base", seed_base, 0, MAX_SEED - n_seeds + 1, 0)
    episodes = whole(fn, "episodes", DEFAULT_EPISODES if episodes is None else episodes, 1,
                      MAX_EPISODES, 300)
    rewards_text = rewards_arg(fn, rewards)
    fid = fidelity_arg(fn, fidelity, "physics" in worlds)
    overrides = settings_arg(fn, settings)
    start, goal = cell_arg(fn, "start", start), cell_arg(fn, "goal", goal)
    if jobs is not None:
        jobs = whole(fn, "jobs", jobs, 1, MAX_JOBS, 2)
    if resume and out is None:
        raise err(fn, "resume", "needs out: the folder whose finished runs to keep",
                   "pass out='DIR' as well, or drop resume")
    sc, _ = problem_of(fn, scenario, start, goal, rewards_text, s_starts, worlds)
    n_pre = pretrain_arg(fn, pretrain, worlds)
    if n_pre:
        carried_methods_arg(fn, "pretrain", names)
    per_method = settings_per_method(names, overrides)

    specs = make_specs(scenario, names, list(range(seed_base, seed_base + n_seeds)), episodes,
                       worlds, per_method, start=start, goal=goal, rewards=rewards_text,
                       fidelity=fid, s_starts=s_starts)
    if n_pre:
        specs = [dataclasses.replace(sp, pretrain=n_pre) if sp.world == "physics" else sp
                 for sp in specs]
    _check_backend(fn, backend, address, start_method)
    rec_path = record_arg(fn, record, scenario_name(scenario).rsplit("/", 1)[-1]
                       .removesuffix(".toml"), "compare")
    recording = None
    if rec_path is not None:
        recording = SweepRecording(
            rec_path, every=whole(fn, "record_every", record_every, 1, MAX_EPISODES, 100),
            values_every=whole(fn, "record_values_every", record_values_every, 1,
                                MAX_EPISODES, 300),
            detail_seeds=whole(fn, "record_seeds", record_seeds, 1, MAX_SEEDS, 1))
    if announce is not None:
        announce(len(specs), names, worlds)
    results = sweep(specs, out, backend_name=backend, jobs=jobs, address=address,
                    start_method=start_method, resume=resume, recording=recording,
                    figures=figures, progress=bool(progress))
    rec = None if rec_path is None else Path(rec_path)
    return Comparison(sc, [Run.from_record(r, rec) for r in results["runs"]], results,
                      None if out is None else Path(out), rec)


def settings_per_method(methods: Sequence[str], overrides: tuple[tuple[str, float], ...]
                        ) -> dict[str, tuple[tuple[str, float], ...]]:
    """``settings`` (``--set``) for every method that has the field; an error only when none
    has it. Every method's config is built here once, so a bad value fails before any run."""
    out: dict[str, tuple[tuple[str, float], ...]] = {}
    for m in methods:
        make_config(m, ())
        fields = set(settable_fields(method_class(m)))
        out[m] = tuple((k, v) for k, v in overrides if k in fields)
        make_config(m, out[m])
    for k, _ in overrides:
        if not any(k in dict(o) for o in out.values()):
            raise ExperimentError("scenarios.api.config", "settings",
                                  f"none of the methods ({', '.join(methods)}) has a field "
                                  f"{k!r}", "use one of their fields: " + ", ".join(sorted(
                                      {f for m in methods
                                       for f in settable_fields(method_class(m))})))
    return out


def _check_backend(fn: str, backend: str, address: str | None,
                   start_method: str | None) -> None:
    if backend not in BACKENDS:
        raise err(fn, "backend", f"is {backend!r}, not a backend", "pass backend='local' or "
                  "backend='ray'")
    if backend == "local" and address is not None:
        raise err(fn, "address", "only applies with the Ray backend",
                  "pass backend='ray', or drop address=...")
    if backend == "local" and start_method not in START_METHODS:
        raise err(fn, "start_method", f"is {start_method!r}",
                  "use 'fork', 'spawn' or 'forkserver' (or None)")


# ---------------------------------------------------------------- grade, route


def grade(policy: np.ndarray | Sequence[int] | Callable[[int], int], scenario: ScenarioLike,
          *, fidelity: Any = "exact", drives: int = 50, seed: int = 0,
          start: Cell | None = None, goal: Cell | None = None,
          with_optimum: bool = True) -> Grade:
    """Drive ``policy`` from S at ``fidelity``, each drive with its own noise stream, exactly
    as the tool grades its own final policies (:mod:`scenarios.runs.physics_grading`): a
    run's final grade is ``grade(run.policy, ..., seed=run.seed)``.

    ``policy``: an action per cell (``int[n_states]``, state = ``iy * nx + ix``) or a
    function of the cell returning an action (e.g. ``lambda s: int(model.predict(s,
    deterministic=True)[0])`` for a Stable-Baselines3 model), called once per cell.
    ``fidelity``: a rung (None: the scenario's own). ``drives``: above ``exact`` (at
    ``exact`` every drive is the same, so it drives once). ``with_optimum``: also build V*
    (cached on disk) and say whether the policy matches it.
    """
    fn = "grade"
    scenario = scenario_arg(fn, scenario)
    fid = fidelity_arg(fn, fidelity, True)
    drives = whole(fn, "drives", drives, 1, MAX_DRIVES, 50)
    seed = whole(fn, "seed", seed, 0, MAX_SEED, 0)
    # no rewards: a grade (P(G), primitives, contacts) does not depend on them
    sc, model = problem_of(fn, scenario, cell_arg(fn, "start", start), cell_arg(fn, "goal", goal),
                           None, None, ["physics"])
    table = policy_table(fn, policy, model.n_states)
    return _graded(sc, model, table, fid or parse_fidelity(sc.physics), drives, seed,
                   with_optimum)[0]


def _graded(sc: Scenario, model: Any, table: np.ndarray, fid: Fidelity, drives: int, seed: int,
            with_optimum: bool) -> tuple[Grade, Any]:
    """:func:`grade` of checked arguments, and its drives (their routes and paths)."""
    grader = Grader(sc, fid)
    st = policy_state(table)
    n = 1 if fid.is_exact else drives
    r = grader.drive(st, n, seed if not fid.is_exact else 0, FINAL_TAG if not fid.is_exact
                     else 0, measure_metres=True, keep_routes=True, keep_path=True)
    summary = r.summary()
    walk, _ = greedy_test(st, model)
    opt = optimum_of(sc, model, fid) if with_optimum else None
    optimal = None
    if opt is not None and opt.expected_primitives is not None:
        if fid.is_exact:
            optimal = bool(r.reached[0]) and int(r.primitives[0]) == opt.physics_route_length
        else:
            with _optimum_always():
                at = optimum_at_fidelity(sc, fid)
            optimal = None if at is None else matches_optimum(summary, at)
    med = summary["primitives_median"]
    return Grade(fid.label, r.n, seed, float(summary["p_goal"]),
                 tuple(summary["p_goal_ci95"]),
                 summary["primitives_mean"], None if med is None else float(med),
                 float(r.contacts.mean()), None if walk < 0 else int(walk), opt, optimal,
                 dict(summary)), r


def route(agent: str | Path, scenario: ScenarioLike, *, world: str = "physics",
          fidelity: Any = None, rewards: Any = None, drives: int = 50, seed: int = 0,
          start: Cell | None = None, goal: Cell | None = None,
          with_optimum: bool = True) -> Route:
    """A saved agent's (``train(..., save=...)``, ``rnhql train --save``) greedy route from S
    against the grid's BFS optimum: ``rnhql route``. ``world="grid"``: its greedy walk on
    the grid; ``"physics"``: its greedy policy driven and graded through :func:`grade` at
    ``fidelity`` (None: the scenario's own), the route shown being the first drive's. The
    :class:`Route`'s ``grade`` fields read through it (``route(...).p_goal``)."""
    fn = "route"
    scenario = scenario_arg(fn, scenario)
    if world not in WORLDS:
        raise err(fn, "world", f"is {world!r}, not a world", f"use one of: {', '.join(WORLDS)}")
    fid = fidelity_arg(fn, fidelity, world == "physics")
    drives = whole(fn, "drives", drives, 1, MAX_DRIVES, 50)
    seed = whole(fn, "seed", seed, 0, MAX_SEED, 0)
    start, goal = cell_arg(fn, "start", start), cell_arg(fn, "goal", goal)
    sc, model = problem_of(fn, scenario, start, goal, rewards_arg(fn, rewards), None, [world])
    ck = load_checkpoint(agent, None, model.n_states, geometry_of(model))
    # an agent trained on another scenario of the same size loads; its route here would
    # mean nothing. The layout is checked, not the rewards or starts: a route ignores them
    ck.check_problem({"layout": layout_digest(scenario, start, goal)})
    optimum = tuple(bfs_route(model.next_state, model.distance_to_goal, model.start))
    length, cells = greedy_test(ck.state, model)
    graded = path = poses = first = None
    if world == "physics":
        graded, r = _graded(sc, model, greedy_actions(ck.state),
                            fid or parse_fidelity(sc.physics), drives, seed, with_optimum)
        cells, path, poses = r.routes[0], r.path, r.poses
        length = len(cells) - 1 if r.reached[0] else -1
        first = {"reached": bool(r.reached[0]), "metres": float(r.metres[0]),
                 "contacts": int(r.contacts[0]), "sim_time_s": float(r.sim_time_s[0])}
    return Route(ck.method, ck.config.name, int(ck.episodes), world, tuple(int(c) for c in cells),
                 int(length), tuple(int(c) for c in optimum), graded, path, poses, first, ck)

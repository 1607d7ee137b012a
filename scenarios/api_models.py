"""rnhql as a library, the physics world as a model: the yardsticks (:func:`optimum`), what
the grid's states cannot see (:func:`aliasing`) and an independent simulator's word
(:func:`crosscheck`). Re-exported by :mod:`scenarios.api` (the one door); ``rnhql
optimum``, ``aliasing`` and ``crosscheck`` print what these return.

Arguments are checked before any work as in :mod:`scenarios.api` (:mod:`scenarios.api_args`).
"""

from __future__ import annotations

import contextlib
import math
import os
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from learning.compiled.readout import greedy_actions
from learning.drivers.checkpoint import load_checkpoint
from learning.geometry import geometry_of
from scenarios.api_args import (
    MAX_DRIVES,
    MAX_SEED,
    ScenarioLike,
    cell_arg,
    err,
    fidelity_arg,
    policy_table,
    problem_of,
    rewards_arg,
    scenario_arg,
    whole,
)
from scenarios.runs.spec import layout_digest
from scenarios.sweep.run import optimum_record
from scenarios.values import Aliasing, Crosscheck, ModelBuild, Optimum
from sim.grid.actions import ACTION_NAMES
from sim.physics.fidelity import PRESETS, Fidelity
from sim.physics.models.aliasing import MAX_REPEATS, entropy_map, measure_aliasing
from sim.physics.models.build import cache_dir, digest, stochastic_model
from sim.physics.models.optimum import continuous_optimum_m
from sim.physics.models.solve import solve
from sim.physics.models.stochastic import (
    ARRIVED,
    FACING,
    MAX_SAMPLES,
    REFINE,
    RESTING,
    Sampling,
    is_resting,
)
from sim.physics.models.stochastic_rollouts import drive_model_policy
from sim.physics.models.transition import physics_model
from sim.physics.static import PhysicsConfig
from sim.scenario import Cell, Scenario

MAX_PAIRS = 10_000  # crosscheck: (cell, action) pairs (IR-SIM drives about 20 a second)

# ---------------------------------------------------------------- optimum


def optimum(scenario: ScenarioLike, *, fidelity: Any = "exact", rewards: Any = None,
            start: Cell | None = None, goal: Cell | None = None, samples: int | None = None,
            seed: int = 0, rollouts: int = 0,
            announce: Callable[[str, str], None] | None = None) -> Optimum:
    """The yardsticks at ``fidelity``: the grid's BFS optimum, the physics world's at exact,
    V*(S) (expected primitives) and P(G) where V* is defined (not where the state is
    hidden: open loop, localisation), and the disc's continuous path. V* comes from the
    stochastic model of the physics world, built by driving (``samples`` drives per (state,
    action), default 1 at exact, else 32; ``seed``) and cached on disk, then solved by
    value iteration; ``Optimum.model`` says what it cost. ``rollouts``: also drive V*'s
    policy that many times as a check (``Optimum.driven``). ``announce``: called with the
    scenario's name and the fidelity once every argument is checked, before any driving."""
    fn = "optimum"
    scenario = scenario_arg(fn, scenario)
    fid = fidelity_arg(fn, fidelity, True) or PRESETS["exact"]
    if samples is not None:
        samples = whole(fn, "samples", samples, 1, MAX_SAMPLES // REFINE, 32)
    seed = whole(fn, "seed", seed, 0, MAX_SEED, 0)
    if rollouts:
        rollouts = whole(fn, "rollouts", rollouts, 1, MAX_DRIVES, 100)
    sc, model = problem_of(fn, scenario, cell_arg(fn, "start", start), cell_arg(fn, "goal", goal),
                           rewards_arg(fn, rewards), None, ["physics"])
    if announce is not None:
        announce(sc.name, fid.label)
    return optimum_of(sc, model, fid, samples, seed, rollouts)


def optimum_of(sc: Scenario, grid: Any, fid: Fidelity, samples: int | None = None,
               seed: int = 0, rollouts: int = 0,
            announce: Callable[[str, str], None] | None = None) -> Optimum:
    """:func:`optimum` of a loaded scenario (``grid``: its grid model); the one path to V*."""
    exact = physics_model(sc).optimal_route_length
    cont = continuous_optimum_m(sc)
    v = p = build = driven = None
    if not fid.hidden_state:
        sampling = Sampling.default(fid, samples, seed)
        cached = (cache_dir() / f"{digest(sc, PhysicsConfig(), fid, sampling)}.npz").exists()
        t0 = time.perf_counter()
        with _optimum_always():
            m = stochastic_model(sc, fid, sampling)
        wall = time.perf_counter() - t0
        solved = solve(m, sc.steps_per_episode)
        at = optimum_record(solved.start)
        v, p = at["expected_primitives"], at["p_goal_within_budget"]
        if math.isinf(solved.start.expected_primitives):
            v = float("inf")
        counts = m.context_counts()
        sp = m.sampling
        build = ModelBuild(
            int(m.n_states), int(counts[ARRIVED]),
            tuple(int(c) for c in counts[FACING:FACING + len(ACTION_NAMES)]),
            int(counts[RESTING:RESTING + len(ACTION_NAMES)].sum()),
            len({(int(c), int(x)) for c, x in zip(m.state_cell, m.state_context, strict=True)
                 if RESTING <= x < FACING}),
            int(m.primitives), float(m.build_s),
            wall if cached and wall < m.build_s else None, int(sp.samples), int(sp.refined),
            int(sp.particles) if is_resting(m.state_context).any() else 0,
            int(sp.particle_samples), int(sp.seed), int(solved.sweeps))
        if rollouts:
            driven = drive_model_policy(sc, m, solved.policy, rollouts, seed=seed + 1)
    return Optimum(fid.label, int(grid.optimal_route_length), int(exact), v, p,
                   int(sc.steps_per_episode), None if cont is None else round(cont, 4),
                   sc.name, build, driven)


@contextlib.contextmanager
def _optimum_always() -> Iterator[None]:
    """V* even where a test sweep switched it off for its sweeps (RNHQL_NO_OPTIMUM)."""
    old = os.environ.pop("RNHQL_NO_OPTIMUM", None)
    try:
        yield
    finally:
        if old is not None:
            os.environ["RNHQL_NO_OPTIMUM"] = old


# ---------------------------------------------------------------- aliasing


def aliasing(scenario: ScenarioLike, *, fidelity: Any = "exact", repeats: int = 20,
             seed: int = 0, rewards: Any = None, start: Cell | None = None,
             goal: Cell | None = None,
             announce: Callable[[str, str], None] | None = None) -> Aliasing:
    """The next-cell distribution of every (cell that reaches G, action), ``repeats`` drives
    each from the poses the robot can be in at ``fidelity`` (``seed``: noise and start
    poses): how far the grid's states alias the physics world's. ``announce``: as
    :func:`optimum`'s."""
    fn = "aliasing"
    scenario = scenario_arg(fn, scenario)
    fid = fidelity_arg(fn, fidelity, True) or PRESETS["exact"]
    repeats = whole(fn, "repeats", repeats, 1, MAX_REPEATS, 20)
    seed = whole(fn, "seed", seed, 0, MAX_SEED, 0)
    sc, model = problem_of(fn, scenario, cell_arg(fn, "start", start), cell_arg(fn, "goal", goal),
                           rewards_arg(fn, rewards), None, ["physics"])
    if announce is not None:
        announce(sc.name, fid.label)
    r = measure_aliasing(sc, model, fid, repeats, seed)
    heat = entropy_map(sc, model, r)
    heat.setflags(write=False)
    return Aliasing(r["scenario"], r["fidelity"], repeats, seed, r["pairs"], r["primitives"],
                    r["seconds"], r["multi_outcome_fraction"], r["mean_entropy_bits"],
                    r["mean_bump_probability"], heat,
                    {k: v for k, v in r.items() if not k.startswith("_")})


# ---------------------------------------------------------------- crosscheck


def crosscheck(scenario: ScenarioLike, *, fidelity: Any = "exact", pairs: int = 60,
               repeats: int = 4, drives: int = 5, seed: int = 0,
               policies: Mapping[str, Any] | None = None,
               agents: Sequence[str | Path] = (), rewards: Any = None,
               start: Cell | None = None, goal: Cell | None = None,
               announce: Callable[[str, str], None] | None = None) -> Crosscheck:
    """The same (cell, action) primitives, and policies, here and in IR-SIM (the
    ``rnhql[crosscheck]`` extra): how far the two simulators agree. ``pairs``: (cell,
    action) pairs, a third from each stratum; ``repeats``: drives per pair (1 at exact);
    ``drives``: drives of each policy from S; ``policies``: name -> ``"optimal"`` (the
    grid's optimal policy), an action per cell or a function of the cell; ``agents``: saved
    agents (``train(..., save=...)``), each driven greedily. ``announce``: called with the
    scenario's name and the fidelity once every argument is checked, before the drives
    (IR-SIM takes a while)."""
    from sim.physics.crosscheck.agreement import (
        CrosscheckOptions,
        grid_optimal_policy,
    )
    from sim.physics.crosscheck.agreement import crosscheck as agreement
    from sim.physics.crosscheck.irsim_world import _irsim, check_rung

    fn = "crosscheck"
    scenario = scenario_arg(fn, scenario)
    fid = fidelity_arg(fn, fidelity, True) or PRESETS["exact"]
    check_rung(fid)  # before any work: a rung IR-SIM cannot model is refused
    _irsim()  # ... and a missing IR-SIM
    options = CrosscheckOptions(pairs=whole(fn, "pairs", pairs, 1, MAX_PAIRS, 60),
                                repeats=whole(fn, "repeats", repeats, 1, MAX_REPEATS, 4),
                                policy_drives=whole(fn, "drives", drives, 1, MAX_DRIVES, 5),
                                seed=whole(fn, "seed", seed, 0, MAX_SEED, 0))
    start, goal = cell_arg(fn, "start", start), cell_arg(fn, "goal", goal)
    sc, model = problem_of(fn, scenario, start, goal, rewards_arg(fn, rewards), None,
                           ["physics"])
    tables = {}
    for name, policy in (policies or {}).items():
        if isinstance(policy, str):
            if policy != "optimal":
                raise err(fn, "policies", f"names {policy!r}, not a policy",
                          "pass 'optimal' (the grid's), an action per cell, or a function")
            tables[name] = grid_optimal_policy(model)
        else:
            tables[name] = policy_table(fn, policy, model.n_states)
    for path in agents:
        ckpt = load_checkpoint(path, None, model.n_states, geometry_of(model))
        ckpt.check_problem({"layout": layout_digest(scenario, start, goal)})
        tables[f"{ckpt.method} ({Path(path).name})"] = greedy_actions(ckpt.state)
    if announce is not None:
        announce(sc.name, fid.label)
    return Crosscheck.of(agreement(sc, model, fid, options, tables))

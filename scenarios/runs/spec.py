"""Multi-seed experiments: a sweep is a list of independent :class:`RunSpec`.

Each spec is run in a worker process (the scenario is resolved again there:
specs are small and picklable, models are cached per process), and becomes one
``runs[]`` record of ``results.json`` (see :mod:`scenarios.runs.results`). The
backend only decides *where* :func:`scenarios.runs.run.run_one` executes, so the local pool and
Ray produce the same records for the same seeds.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
from collections.abc import Iterable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from learning.compiled.readout import greedy_actions
from learning.config import LIMITS, limit_problem
from learning.drivers.train import TrainResult
from learning.methods.registry import METHODS, config_class
from learning.metrics import (
    episodes_to_first_optimal,
    episodes_to_stable_optimal,
    optimal_test_fraction,
    reward_per_step,
)
from learning.plain.learner import LearnerClassError
from scenarios.runs.statistics import quantile
from sim.errors import InputError
from sim.grid import TabularModel, build_model
from sim.physics.fidelity import Fidelity, parse_fidelity
from sim.scenario import Cell, Scenario, rewards_from_text, validate_shape
from sim.scenario_io import resolve_scenario

WORLDS = ("grid", "physics")
# a physics episode drives a primitive per step (milliseconds each): 100,000 steps is
# minutes per episode, far beyond any arena's longest route (ost003d's budget is 1,704)
MAX_PHYSICS_STEPS_PER_EPISODE = 100_000


class ExperimentError(InputError):
    """A bad method name, config override or world."""


@dataclass(frozen=True)
class RecordOptions:
    """How one run is recorded for Rerun. Not part of the run's key: a recorded run equals
    an unrecorded one (the recorder draws no random numbers)."""

    path: str  # the .rrd to write
    every: int = 10  # episodes recorded in full: the first, every N-th, the last [episodes]
    values_every: int = 300  # value heat maps every K episodes [episodes]
    detail: bool = True  # False: curves only (comparisons, beyond the first seeds)
    prefix: str = ""  # entity subtree (comparisons: runs/<label>/s<seed>)
    recording_id: str | None = None  # shared by the parts of one comparison


@dataclass(frozen=True)
class RunSpec:
    """One training run: everything needed to reproduce it."""

    scenario: str | Scenario  # built-in name, .toml or .map path, or a Scenario built in Python
    method: str  # CLI name, e.g. "rnh-ql", or module:Class of a learner of one's own
    seed: int
    episodes: int
    world: str = "grid"
    overrides: tuple[tuple[str, float], ...] = ()  # config field -> value (sweeps)
    start: Cell | None = None  # for a .map (Moving AI frame)
    goal: Cell | None = None
    test_every: int = 10  # greedy test from S every N episodes
    rewards: str | None = None  # --rewards: a scheme name or goal=..,bump=..,step=.. (None: the
    #                             scenario's own)
    drive_final: bool = False  # grid runs: also drive the final greedy policy in physics
    fidelity: Fidelity | None = None  # --fidelity of the physics world (None: the
    #   scenario's own [physics] table, else exact); text is parsed once, here
    s_starts: float | None = None  # --s-starts: share of episodes starting at S (None: the
    #                                scenario's own s_start_share)
    recording: RecordOptions | None = None  # None: not recorded (never part of the key)
    pretrain: int = 0  # physics runs: episodes in the grid first, on the run's own learner
    #                    and start streams, then ``episodes`` at the rung (0: from scratch)

    def __post_init__(self) -> None:
        if isinstance(self.fidelity, str):  # a study's "noisy": the one parse of the text
            object.__setattr__(self, "fidelity", parse_fidelity(self.fidelity))

    @property
    def scenario_name(self) -> str:
        """The scenario as a key and a file name see it: its name or path."""
        return self.scenario if isinstance(self.scenario, str) else self.scenario.name

    @property
    def problem(self) -> tuple[str | Scenario, Cell | None, Cell | None, str | None,
                               float | None]:
        """What :func:`load` needs: (scenario, start, goal, rewards, s_starts)."""
        return self.scenario, self.start, self.goal, self.rewards, self.s_starts

    @property
    def key(self) -> str:
        """A stable id of everything that changes the run, for resuming sweeps.

        The scenario enters by name *and* content digest (a ``.map`` with other
        ``--start/--goal``, or an edited TOML, is another run), then start, goal,
        world, method, config overrides, greedy-test cadence, seed and episodes.
        Recording options are left out: a recorded run equals an unrecorded one.
        """
        extra = "".join(f",{k}={v:g}" for k, v in self.overrides)
        cells = "".join(f"|{n}={c[0]},{c[1]}" for n, c in (("S", self.start), ("G", self.goal))
                        if c is not None)
        fid = "" if self.fidelity_spec.is_exact else f"|fid={self.fidelity_spec.label}"
        return (f"{self.scenario_name}#{scenario_digest(*self.problem)}"
                f"{cells}|{self.world}{fid}|{self.method}{extra}|t{self.test_every}"
                f"|s{self.seed}|e{self.episodes}"
                + (f"|pre-grid{self.pretrain}" if self.pretrain else ""))

    @functools.cached_property
    def fidelity_spec(self) -> Fidelity:
        """--fidelity, else the scenario's ``[physics]`` table, else exact."""
        if self.fidelity is not None:
            return self.fidelity
        return parse_fidelity(load(*self.problem)[0].physics)


@lru_cache(maxsize=8)
def load(scenario: str | Scenario, start: Cell | None = None, goal: Cell | None = None,
         rewards: str | None = None, s_starts: float | None = None
         ) -> tuple[Scenario, TabularModel]:
    """The scenario (with ``rewards`` replacing its own scheme and ``s_starts`` its share of
    episodes starting at S, if given) and its grid model."""
    sc = resolve_scenario(scenario, start, goal)
    if rewards is not None:
        sc = dataclasses.replace(sc, rewards=rewards_from_text(rewards))
    if s_starts is not None:
        sc = dataclasses.replace(sc, s_start_share=float(s_starts))
        validate_shape(sc)
    return sc, build_model(sc)


@lru_cache(maxsize=64)
def scenario_digest(scenario: str | Scenario, start: Cell | None = None, goal: Cell | None = None,
                    rewards: str | None = None, s_starts: float | None = None) -> str:
    """12 hex digits of a hash of what the scenario *is*: its resolved content (geometry,
    robot, rewards, episode length, S, G), not the file it came from."""
    sc, _ = load(scenario, start, goal, rewards, s_starts)
    fields = {k: v for k, v in dataclasses.asdict(sc).items()
              if k not in ("name", "source", "description")
              and not (k == "physics" and v is None)  # (digests from before these fields hold)
              and not (k == "s_start_share" and v == 0.0)}
    blob = json.dumps(fields, sort_keys=True, default=repr).encode()
    return hashlib.sha256(blob).hexdigest()[:12]


@lru_cache(maxsize=64)
def layout_digest(scenario: str | Scenario, start: Cell | None = None,
                  goal: Cell | None = None) -> str:
    """12 hex digits of a hash of the route problem's layout alone: arena, obstacles, robot,
    S, G and episode length; not the rewards or the share of starts at S. What a saved
    agent's greedy route depends on, so what ``rnhql route`` checks a checkpoint against."""
    sc, _ = load(scenario, start, goal)
    fields = {k: v for k, v in dataclasses.asdict(sc).items()
              if k not in ("name", "source", "description", "rewards", "s_start_share",
                           "physics")}
    blob = json.dumps(fields, sort_keys=True, default=repr).encode()
    return hashlib.sha256(blob).hexdigest()[:12]


CONFIG = "scenarios.api.config"  # a method's config, built from the call's method and settings


def method_class(method: str) -> type:
    """The config class of ``method``: a registered name, or ``module:Class`` (a compiled
    method's config or a plain-Python learner: :func:`learning.methods.registry.config_class`)."""
    try:
        return config_class(method)
    except LearnerClassError as exc:  # found, but not to the protocol: the class is the fix
        raise ExperimentError(CONFIG, "method", str(exc).removesuffix("."),
                              "fix the class to the protocol docs/python-api.md gives for a "
                              "learner of your own") from None
    except ValueError as exc:
        raise ExperimentError(CONFIG, "method", str(exc).removesuffix("."),
                              "name a method of docs/methods.md (rnhql train --help lists "
                              "them), or module:Class of a learner of your own "
                              "(docs/python-api.md)") from None


def settable_fields(cls: type) -> list[str]:
    """The config fields ``--set`` may change: not those the method's rules ignore, none of
    a plain learner's (its settings are its own)."""
    return list(cls.settable())


def make_config(method: str, overrides: Iterable[tuple[str, float]] = ()):
    """The method's frozen config with paper defaults, fields overridden by name."""
    cls = method_class(method)
    names = {f.name: f for f in dataclasses.fields(cls) if f.name in settable_fields(cls)}
    kwargs: dict[str, Any] = {}
    for k, v in overrides:
        if k in getattr(cls, "IGNORED", ()):
            raise ExperimentError(CONFIG, "settings", f"{method}'s rules do not read {k} (it "
                                  "inherits the field)",
                                  f"drop {k}, or use method='{cls.reader_of(k)}'")
        if k not in names:
            wider = [c.cli for c in METHODS.values()  # e.g. rnh-ql+ablation, for rnh-ql+
                     if issubclass(c, cls) and k in {f.name for f in dataclasses.fields(c)}]
            raise ExperimentError(CONFIG, "settings", f"{method} has no field {k!r}",
                                  (f"use one of: {', '.join(names)}" if names else
                                   "it has no settings to change: set them in its class")
                                  + (f"; or method='{wider[0]}', which has {k}" if wider
                                     else ""))
        problem = limit_problem(k, float(v))
        if problem is not None:
            limit = LIMITS.get(k, (None,))[0]
            raise ExperimentError(CONFIG, "settings", f"{k}={v:g}: {problem}",
                                  f"pass at most {limit:g} for {k}" if limit is not None
                                  else f"pass a finite number for {k}")
        if names[k].type in (int, "int", bool, "bool"):
            if not float(v).is_integer():
                raise ExperimentError(CONFIG, "settings", f"{k}={v:g}: {method}'s {k} is a "
                                      "whole number", f"pass a whole number for {k}, e.g. "
                                      f"{int(v)}")
            kwargs[k] = bool(v) if names[k].type in (bool, "bool") else int(v)
        else:
            kwargs[k] = v
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise ExperimentError(CONFIG, "settings", str(exc), "pick a valid value") from None


@dataclass(frozen=True)
class RunOutcome:
    """A finished run, the same for both worlds: what :func:`run_record` turns into a
    ``runs[]`` entry. ``result`` is the one record of what a run measured
    (:class:`learning.drivers.train.TrainResult`; a physics run's
    :class:`scenarios.runs.physics.PhysicsTrainResult` is one, with what its world graded);
    the outcome adds what a sweep measures after training."""

    result: TrainResult
    epsilon_route_lengths: np.ndarray  # int[k]; the paper's test: epsilon-greedy rollouts
    world_extras: dict[str, Any]  # world-specific fields of the record (physics, drives)
    policy: np.ndarray | None = None  # int[nS]; the final greedy action of every cell

    @classmethod
    def of(cls, result: TrainResult, epsilon_route_lengths: np.ndarray,
           world_extras: dict[str, Any] | None = None) -> RunOutcome:
        """From a finished run's result (a physics one carries its own extras)."""
        extras = dict(getattr(result, "world_extras", {}))
        extras.update(world_extras or {})
        return cls(result, np.asarray(epsilon_route_lengths), extras,
                   greedy_actions(result.state))


def run_record(spec: RunSpec, cfg: Any, outcome: RunOutcome) -> dict[str, Any]:
    """One ``runs[]`` entry of results.json from a finished run.

    The figures come from :mod:`learning.metrics` (one definition each); the
    per-episode arrays (steps, return) let a script compute any window's reward
    per step as a ratio of sums.
    """
    result = outcome.result
    steps = np.asarray(result.steps)
    returns = np.asarray(result.returns)
    optimal = int(result.optimal_length)
    final_len = int(result.final_route_length)
    test_e = np.asarray(result.test_episodes).astype(int)
    test_l = np.asarray(result.test_route_length).astype(int)
    tail = max(1, steps.size // 10)
    return {
        "key": spec.key,
        "method": spec.method,
        "method_name": type(cfg).name,
        "seed": spec.seed,
        "world": spec.world,
        # physics runs: the world trained in; grid runs: the world their policy was driven in
        "fidelity": (spec.fidelity_spec.label
                     if spec.world == "physics" or spec.drive_final else None),
        "config": cfg.record_fields(),
        "optimal_route_length": optimal,
        "episodes_to_stable_optimal": episodes_to_stable_optimal(test_e, test_l, optimal),
        "episodes_to_optimal": episodes_to_first_optimal(test_e, test_l, optimal),
        "optimal_test_fraction": optimal_test_fraction(test_l, optimal),
        "final_route_length": final_len,
        "final_route_optimal": final_len == optimal,
        "final_route_excess": None if final_len < 0 else final_len - optimal,
        "final_route": [int(s) for s in result.final_route],
        "epsilon_route_length": _median_route(outcome.epsilon_route_lengths),
        "success_rate": float(np.mean(result.success)),
        "reward_per_step": reward_per_step(returns, steps),
        "reward_per_step_last_10pct": reward_per_step(returns[-tail:], steps[-tail:]),
        "wall_time_s": float(np.sum(result.wall_time_s)),
        "env_steps": int(steps.sum()),
        "optimal_action_fraction": float(result.optimal_action_fraction),
        "steps_per_episode": steps.astype(int).tolist(),
        "return_per_episode": np.round(returns, 6).tolist(),
        "success_per_episode": np.asarray(result.success).astype(int).tolist(),
        "wall_time_per_episode_s": np.round(np.asarray(result.wall_time_s), 9).tolist(),
        "test_episodes": test_e.tolist(),
        "test_route_length": test_l.tolist(),
        "greedy_policy": policy_text(outcome.policy),
        **outcome.world_extras,
    }


def policy_text(policy: np.ndarray | None) -> str | None:
    """A policy as one digit per cell, state order (``"0"`` up, ``"1"`` down, ``"2"`` left,
    ``"3"`` right): 1 byte a cell in results.json; :func:`policy_from_text` reads it back."""
    if policy is None:
        return None
    return (np.asarray(policy, dtype=np.uint8) + ord("0")).tobytes().decode("ascii")


def policy_from_text(text: str) -> np.ndarray:
    """int64[nS] from :func:`policy_text`."""
    return np.frombuffer(text.encode("ascii"), dtype=np.uint8).astype(np.int64) - ord("0")


def _median_route(lengths: np.ndarray) -> float | None:
    """Median route length of rollouts, a rollout that missed G counting as infinite."""
    v = quantile([None if x < 0 else float(x) for x in lengths], 0.5)
    return None if not np.isfinite(v) else v


def physics_budget(sc, worlds: list[str] | tuple[str, ...]) -> None:
    """A physics run's episode length within :data:`MAX_PHYSICS_STEPS_PER_EPISODE` (the
    grid's own limit is the scenario's, far larger: a grid step is nanoseconds)."""
    if "physics" in worlds and sc.steps_per_episode > MAX_PHYSICS_STEPS_PER_EPISODE:
        raise ExperimentError(sc.source, "steps_per_episode", f"{sc.steps_per_episode:,} "
                              f"steps is more than the limit of "
                              f"{MAX_PHYSICS_STEPS_PER_EPISODE:,} for a physics run",
                              f"use at most {MAX_PHYSICS_STEPS_PER_EPISODE:,} (or --world grid)")

"""What :mod:`scenarios.api` returns: typed, frozen values, read from the records the tool
writes (a run's ``results.json`` entry), so a script and the CLI see the same figures.

- :class:`Run`: one trained run (one method, world, seed);
- :class:`Comparison`: a sweep's runs, its ``results.json`` payload, and how to write it;
- :class:`Grade`: a policy driven from S at a fidelity, as the tool grades its own;
- :class:`Route`: a saved agent's greedy route from S, driven where asked;
- :class:`TrainPlan`: what a call of ``train`` is about to run (its ``announce``);
- :class:`Optimum`: the yardsticks: the grid's BFS optimum, the physics world's at
  ``exact``, V* at the fidelity where it is defined, the disc's continuous path
  (:class:`ModelBuild`: how V* was found);
- :class:`Aliasing`: how many next cells a (cell, action) can lead to at a fidelity;
- :class:`Crosscheck`: how far this physics and IR-SIM agree (:class:`Stratum`,
  :class:`PolicyAgreement`).

In a Jupyter notebook a value with a recording shows it inline (:meth:`Run.show`; needs
the ``rnhql[notebook]`` extra, Rerun's notebook viewer).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from learning.config import MethodConfig
from learning.plain.learner import located_name
from scenarios.figures.plots import all_figures
from scenarios.runs.results import summary_markdown, write_results
from scenarios.runs.spec import load, policy_from_text
from scenarios.sweep.brief import summary_terminal
from scenarios.sweep.outdir import check_out_dir
from scenarios.sweep.run import ctrl_c_held
from sim.scenario import Scenario


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


def _readonly(d: Mapping[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(dict(d))


def _in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (where a widget can be drawn)."""
    try:
        from IPython import get_ipython  # optional: only notebooks have it
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and "IPKernelApp" in getattr(shell, "config", {})


def show_recording(path: Path | None, width: int = 1000, height: int = 640) -> Any:
    """Rerun's notebook viewer on ``path`` (the ``rnhql[notebook]`` extra). Its script and
    viewer are served from this machine (``RERUN_NOTEBOOK_ASSET=serve-local``, unless set
    otherwise), so it draws offline too; outside a notebook it says what to run instead."""
    if path is None:
        raise ValueError("this value has no recording: pass record=True (or a .rrd path)")
    if not _in_notebook():
        print(f"show() draws in a Jupyter notebook; here, open the recording with: rnhql view "
              f"{path}  (or rnhql view {path} --web)", file=sys.stderr)
        return None
    os.environ.setdefault("RERUN_NOTEBOOK_ASSET", "serve-local")  # read at its import
    try:
        # optional (rnhql[notebook]); 335 ms at import
        from rerun.notebook import Viewer
    except ImportError:
        raise ImportError("showing a recording in a notebook needs Rerun's notebook viewer: "
                          "pip install 'rnhql[notebook]'") from None
    viewer = Viewer(width=width, height=height)
    viewer._flush_hook(Path(path).read_bytes())  # the viewer's own way in for .rrd bytes
    return viewer


@dataclass(frozen=True, eq=False)
class Run:
    """One training run, from its ``results.json`` record (:attr:`record`, read-only)."""

    method: str  # the method's name in the sweep: "rnh-ql+", or "module:Class"
    method_name: str  # how tables name it
    world: str  # "grid" or "physics"
    fidelity: str | None  # the physics world's rung (None: a grid run)
    seed: int
    episodes: int
    final_route_length: int | None  # the final greedy test from S [moves]; None: G missed
    optimal_route_length: int  # the optimum of the world the run was graded in [moves]
    episodes_to_stable_optimal: int | None  # None: never stably optimal
    success_rate: float  # share of training episodes that reached G
    policy: np.ndarray  # int[n_states]: the final greedy action of every cell (read-only;
    #                     empty for a run resumed from a record written before the field)
    p_goal: float | None  # physics above exact: P(G) of the final policy's drives
    p_goal_ci95: tuple[float, float] | None
    wall_time_s: float  # [s]
    record: Mapping[str, Any] = field(repr=False)  # the results.json entry
    recording: Path | None = None  # the .rrd it was recorded to, if it was
    carried: Any = field(default=None, repr=False)  # the trained learner, for ``init=`` of a
    #   next run (scenarios.runs.warm.Carried; None for a run read from results.json)

    @property
    def pretrain(self) -> Mapping[str, Any] | None:
        """The first phase of a warm-started run (its world, episodes, moves or robot
        primitives and seconds, and its policy graded here before this phase), or None."""
        return self.record.get("pretrain")

    @property
    def robot_primitives(self) -> int | None:
        """Primitives the robot drove in this run's physics phase (None: a grid run)."""
        return int(self.record["env_steps"]) if self.world == "physics" else None

    @property
    def robot_seconds(self) -> float | None:
        """Simulated seconds the robot drove in this run's physics phase (None: grid)."""
        v = self.record.get("robot_seconds")
        return None if v is None else float(v)

    @property
    def final_route_optimal(self) -> bool:
        return self.final_route_length == self.optimal_route_length

    @classmethod
    def from_record(cls, rec: Mapping[str, Any], recording: Path | None = None) -> Run:
        pol = rec.get("final_policy") or {}
        above = rec.get("world") == "physics" and (rec.get("fidelity") or "exact") != "exact"
        length = int(rec["final_route_length"])
        return cls(
            method=str(rec["method"]), method_name=str(rec["method_name"]),
            world=str(rec["world"]), fidelity=rec.get("fidelity"), seed=int(rec["seed"]),
            episodes=len(rec["steps_per_episode"]),
            final_route_length=None if length < 0 else length,
            optimal_route_length=int(rec["optimal_route_length"]),
            episodes_to_stable_optimal=rec.get("episodes_to_stable_optimal"),
            success_rate=float(rec["success_rate"]),
            policy=_frozen(policy_from_text(rec["greedy_policy"]) if rec.get("greedy_policy")
                           else np.zeros(0, np.int64)),  # (records from before the field)
            p_goal=float(pol["p_goal"]) if above and pol else None,
            p_goal_ci95=tuple(pol["p_goal_ci95"]) if above and pol else None,
            wall_time_s=float(rec["wall_time_s"]), record=_readonly(rec),
            recording=None if recording is None else Path(recording))

    def show(self, width: int = 1000, height: int = 640) -> Any:
        """The run's recording in a notebook (Rerun's notebook viewer)."""
        return show_recording(self.recording, width, height)

    def __str__(self) -> str:
        where = self.world if self.fidelity is None else f"{self.world} at {self.fidelity}"
        route = ("G not reached" if self.final_route_length is None
                 else f"{self.final_route_length} moves")
        stable = ("never" if self.episodes_to_stable_optimal is None
                  else f"after {self.episodes_to_stable_optimal} episodes")
        p = "" if self.p_goal is None else f", P(G) {self.p_goal:.2f}"
        return (f"{self.method_name} ({where}, seed {self.seed}): final route {route} "
                f"(optimal {self.optimal_route_length}){p}, stably optimal {stable}")


@dataclass(frozen=True, eq=False)
class Comparison:
    """A sweep: its runs (spec order) and its ``results.json`` payload (read-only)."""

    scenario: Scenario  # as run (rewards and starts applied)
    runs: list[Run]
    results: Mapping[str, Any] = field(repr=False)
    out: Path | None = None  # where its files were written (None: nowhere yet)
    recording: Path | None = None

    @property
    def methods(self) -> list[str]:
        return list(dict.fromkeys(r.method for r in self.runs))

    def of(self, method: str | type, world: str = "grid") -> list[Run]:
        """The runs of one method (a name or the learner class given) in one world."""
        name = method if isinstance(method, str) else _method_key(method)
        return [r for r in self.runs if r.method == name and r.world == world]

    def summary(self) -> str:
        """The text of ``summary.md``: medians with quartiles and intervals, the verdict."""
        return summary_markdown(dict(self.results), self.methods)

    def brief(self, width: int = 100) -> str:
        """What ``rnhql compare`` prints: a compact table and the verdict's headlines, every
        line within ``width`` columns (:meth:`summary` has the full tables)."""
        return summary_terminal(dict(self.results), self.methods, width)

    def save(self, out: str | Path, figures: bool = True) -> Path:
        """Write ``results.json``, ``summary.md`` and (``figures``) the figures to ``out``, as
        ``rnhql compare --out`` does; returns the folder."""
        out = check_out_dir(Path(out), "out")
        results = dict(self.results)
        write_results(out, results, self.methods)
        if figures:
            _, model = load(self.scenario)
            with ctrl_c_held():
                all_figures(results, self.scenario, model, out)
        return out

    def show(self, width: int = 1000, height: int = 640) -> Any:
        """The comparison's recording in a notebook (Rerun's notebook viewer)."""
        return show_recording(self.recording, width, height)

    def __str__(self) -> str:
        return self.summary()


def _method_key(cls: type) -> str:
    return cls.cli if issubclass(cls, MethodConfig) else located_name(cls)


@dataclass(frozen=True, eq=False)
class Route:
    """A saved agent's greedy route from S against the grid's BFS optimum (``rnhql route``).
    In the physics world its policy was driven and graded: ``grade`` (whose fields read
    through, ``route.p_goal``), the route shown being the first drive's."""

    method: str  # the registry's name
    name: str  # as tables name it
    episodes: int  # the agent trained
    world: str  # "grid": the greedy walk; "physics": driven
    cells: tuple[int, ...]  # the route shown, S first
    length: int  # its moves (-1: G not reached)
    optimal_cells: tuple[int, ...]  # a shortest route on the grid (BFS), S first
    grade: Grade | None  # physics: every drive at the fidelity
    path: np.ndarray | None  # physics: the first drive's poses, float64[m, 3] [m, m, rad]
    poses: np.ndarray | None  # physics: its pose at S and after each primitive
    first_drive: Mapping[str, Any] | None  # physics: reached, metres, contacts, sim_time_s
    agent: Any = field(repr=False, default=None)  # the loaded checkpoint (state, config)

    @property
    def optimal(self) -> bool:
        """Whether the route shown is as short as the BFS optimum."""
        return self.length == len(self.optimal_cells) - 1

    def __getattr__(self, name: str) -> Any:
        grade = self.__dict__.get("grade")
        if grade is None or name.startswith("_"):
            raise AttributeError(name)
        return getattr(grade, name)

    def __str__(self) -> str:
        shown = "G not reached" if self.length < 0 else f"{self.length} moves"
        return (f"{self.name} greedy route ({self.world}): {shown} "
                f"({'optimal' if self.optimal else 'not optimal'}); BFS optimum "
                f"{len(self.optimal_cells) - 1} moves")


@dataclass(frozen=True)
class TrainPlan:
    """What :func:`scenarios.api.train` is about to run, every argument checked, before any
    training (its ``announce`` callback gets it: the command prints its first lines there)."""

    method: str  # as tables name it
    scenario: Scenario
    world: str  # "grid" or "physics"
    fidelity: str | None  # the rung's label (physics), else None
    seed: int
    episodes: int
    resumed_episodes: int | None  # episodes already in the checkpoint resumed, else None
    pretrain: int  # grid episodes first (0: none)


@dataclass(frozen=True)
class ModelBuild:
    """How V* was found: the stochastic model of the physics world at the fidelity, built by
    driving (:mod:`sim.physics.models.build`, cached on disk) and solved by value iteration."""

    states: int  # model states (cell, context[, rest pose])
    arrived: int  # states of a robot that arrived on a cell centre
    facing: tuple[int, ...]  # ... arrived facing each action's direction (up, down, left, right)
    resting: int  # states of a robot resting where a contact left it
    resting_pairs: int  # (cell, bumped action) pairs those rest poses come from
    primitives: int  # driven to build it
    build_s: float  # what building it cost [s]
    loaded_s: float | None  # what loading it from the disk cache took [s] (None: built now)
    samples: int  # drives per (state, action)
    refined: int  # ... where they disagreed
    particles: int  # rest poses per (cell, bumped action)
    particle_samples: int  # drives per rest pose
    seed: int
    sweeps: int  # of value iteration


@dataclass(frozen=True)
class Optimum:
    """The yardsticks of a scenario at a fidelity (``model``, ``driven``: how V* was found
    and checked; not compared: two equal optima may come from a build and a cache load)."""

    fidelity: str
    grid_route_length: int  # BFS moves S -> G on the grid (-1: none)
    physics_route_length: int  # the physics world's at exact [primitives] (-1: none)
    expected_primitives: float | None  # V*(S) at the fidelity (None: not defined there)
    p_goal_within_budget: float | None  # P(G) within the episode under V*'s policy
    budget: int  # the episode's primitives
    continuous_route_m: float | None  # the disc's any-angle path [m]
    scenario: str = ""  # its name
    model: ModelBuild | None = field(default=None, compare=False)
    driven: Any = field(default=None, compare=False)  # RolloutStats of V*'s policy, if asked

    def __str__(self) -> str:
        v = ("undefined (hidden state)" if self.expected_primitives is None
             else "inf" if math.isinf(self.expected_primitives)
             else f"{self.expected_primitives:.2f} expected primitives")
        return (f"optimum at {self.fidelity}: V*(S) {v}; exact physics "
                f"{self.physics_route_length}, grid {self.grid_route_length} moves")


@dataclass(frozen=True)
class Aliasing:
    """How many next cells one (cell, action) can lead to at a fidelity
    (:mod:`sim.physics.models.aliasing`): what the grid's states cannot see."""

    scenario: str
    fidelity: str
    repeats: int  # drives per (cell, action)
    seed: int
    pairs: int  # (cell that reaches G, action) pairs driven
    primitives: int
    seconds: float  # driving them [s]
    multi_outcome_fraction: float  # share of pairs with more than one next cell
    mean_entropy_bits: float  # of the next-cell distribution, over the pairs
    mean_bump_probability: float
    heat_map: np.ndarray  # float64[ny, nx]: a cell's largest next-cell entropy (nan: none)
    record: Mapping[str, Any]  # aliasing.json's figures, per pair too

    def __str__(self) -> str:
        return (f"{self.scenario}, fidelity {self.fidelity}: {self.pairs} (cell, action) "
                f"pairs x {self.repeats} drives in {self.seconds:.1f} s; "
                f"multi_outcome_fraction {self.multi_outcome_fraction:.4f}, mean entropy "
                f"{self.mean_entropy_bits:.4f} bits, mean bump probability "
                f"{self.mean_bump_probability:.4f}")


@dataclass(frozen=True)
class Stratum:
    """One stratum of a crosscheck's (cell, action) pairs: how far the simulators agree
    (None: the map has no pair of it)."""

    pairs: int
    bump_agree: float | None  # share of pairs whose majority bump-or-not agrees
    bump_gap: float | None  # mean |P(bump) here - P(bump) in IR-SIM|
    class_agree: float | None  # share whose most frequent outcome class agrees
    tv: float | None  # mean total variation distance of the outcome classes
    p_bump_ours: float | None
    p_bump_irsim: float | None


@dataclass(frozen=True)
class PolicyAgreement:
    """One policy driven from S in both simulators."""

    drives: int
    p_goal_rnhql: float
    p_goal_irsim: float
    primitives_rnhql: float | None  # mean over the drives that reached G
    primitives_irsim: float | None


@dataclass(frozen=True)
class Crosscheck:
    """The same primitives, and policies, here and in IR-SIM
    (:mod:`sim.physics.crosscheck.agreement`)."""

    scenario: str
    fidelity: str
    pairs: int
    repeats: int  # drives per pair in each simulator
    primitives: int
    seed: int
    strata: Mapping[str, Stratum]  # grid-blocked, free-near-obstacle, free-open, all
    seconds_rnhql: float
    seconds_irsim: float
    policies: Mapping[str, PolicyAgreement]

    @classmethod
    def of(cls, r: Mapping[str, Any]) -> Crosscheck:
        """From the dict :func:`sim.physics.crosscheck.agreement.crosscheck` returns."""
        return cls(r["scenario"], r["fidelity"], r["pairs"], r["repeats"], r["primitives"],
                   r["seed"], _readonly({k: Stratum(**v) for k, v in r["strata"].items()}),
                   r["seconds"]["rnhql"], r["seconds"]["irsim"],
                   _readonly({k: PolicyAgreement(**v) for k, v in r["policies"].items()}))

    def as_dict(self) -> dict[str, Any]:
        """The JSON form (``--json``, the artifact): the figures as the simulators gave them."""
        return {"scenario": self.scenario, "fidelity": self.fidelity, "pairs": self.pairs,
                "repeats": self.repeats, "primitives": self.primitives, "seed": self.seed,
                "strata": {k: asdict(v) for k, v in self.strata.items()},
                "seconds": {"rnhql": self.seconds_rnhql, "irsim": self.seconds_irsim},
                "policies": {k: asdict(v) for k, v in self.policies.items()}}


@dataclass(frozen=True)
class Grade:
    """A policy driven from S at a fidelity, as the tool grades its own final policies."""

    fidelity: str
    drives: int  # drives from S (1 at exact: every drive is the same)
    seed: int  # the drives' noise streams (a run's grading uses its seed)
    p_goal: float  # share of drives that reached G
    p_goal_ci95: tuple[float, float]  # Wilson 95 % interval
    mean_primitives: float | None  # over the drives that reached G
    median_primitives: float | None  # over all drives, a miss counting as infinite
    contacts_per_drive: float
    grid_route_length: int | None  # the policy's greedy walk on the grid (None: G missed)
    optimum: Optimum | None  # V* and the other yardsticks (None: not asked for)
    optimal: bool | None  # matches V* within its tolerance (None: V* not defined)
    record: Mapping[str, Any] = field(repr=False, default_factory=dict)  # final_policy fields

    def __str__(self) -> str:
        lo, hi = self.p_goal_ci95
        prims = "—" if self.mean_primitives is None else f"{self.mean_primitives:.1f}"
        tail = "" if self.optimal is None else (", optimal at this fidelity" if self.optimal
                                                else ", not optimal at this fidelity")
        return (f"at {self.fidelity}, {self.drives} drive(s): P(G) {self.p_goal:.2f} "
                f"[{lo:.2f}, {hi:.2f}], {prims} primitives, {self.contacts_per_drive:.1f} "
                f"contacts per drive{tail}")

"""Learn in one world, finish in another: what a learner carries from the grid (or a lower
rung) into training at a physics rung.

The grid and every rung share states and actions, so a learner's whole state carries over:
a compiled method's named state (Q, model, potential, counts; traces reset by its ``begin``
at the first episode, as within one world; a method may define a ``carry`` hook, e.g. the
multi-fidelity R-max marks the moves it knew below), or a plain-Python learner's object
(a copy of it: a :class:`~scenarios.values.Run` stays what it was). Its learner and start
streams continue where the first phase left them, so ``train(grid, seed=s)`` then
``train(physics, init=that run, seed=s)`` is the run ``compare(..., pretrain=("grid", n))``
makes for seed ``s`` (tested). The physics noise stream is the rung's own (the seed's).

Each phase is counted in its own currency in the record's ``pretrain`` entry (grid
episodes and moves, or robot primitives and robot seconds), beside the rung's own.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from learning.compiled.named_state import copy_state
from learning.drivers.checkpoint import CheckpointError, load_checkpoint
from learning.drivers.plain_train import train_grid
from learning.methods.registry import n_states_of
from learning.plain.compiled import copied, is_jit_learner
from learning.plain.learner import is_plain, snapshot
from sim.errors import InputError
from sim.grid.actions import N_ACTIONS


@dataclass(frozen=True, eq=False)
class Carried:
    """A trained learner as the next world's run starts from it."""

    method: str  # its name in a sweep ("rnh-ql+", "module:Class")
    config: Any  # its config in the phase that trained it
    state: Any  # a compiled method's named state (None for a plain learner)
    learner: Any  # a plain learner's object (None for a compiled method)
    learner_rng: dict | None  # its learner stream's bit-generator state after the phase
    start_rng: dict | None  # its start stream's, likewise (None: the new run's own)
    phase: dict[str, Any]  # the record of the phase that trained it (world, episodes, ...)
    layout: str | None  # the layout digest of the scenario it was trained on
    n_states: int
    source: str  # what it came from, for messages: "init (a Run)", "agent.npz"
    rewards: str | None = None  # the reward scheme it learned under (its label)

    @property
    def plain(self) -> bool:
        return self.learner is not None

    def starting_learner(self) -> Any:
        """What the next run's agent starts from: a copy of the state or learner (the one
        carried stays as it was, so a Run can seed several runs alike)."""
        if not self.plain:
            return self.state
        if is_jit_learner(self.learner):  # numba's instances do not pickle: field by field
            return copied(self.learner, type(self.config).learner, self.n_states, N_ACTIONS)
        return copy.deepcopy(self.learner)

    def generators(self, learner: np.random.Generator, starts: np.random.Generator
                   ) -> tuple[np.random.Generator, np.random.Generator]:
        """The learner and start streams of the next phase: the carried ones continued where
        they are known, else the new run's own (``learner``, ``starts``)."""
        return (_continued(self.learner_rng, learner), _continued(self.start_rng, starts))

    def policy_state(self, n_actions: int) -> Any:
        """The greedy policy it starts the next world with, as a gradable state (a copy:
        reading a model learner's policy fills its scratch arrays)."""
        if not self.plain:
            return copy_state(self.state)
        return snapshot(self.learner, self.config, self.n_states, n_actions)

    def check(self, method: str, layout: str, n_states: int, rewards: str, arg: str,
              where: str) -> None:
        """An :class:`InputError` (before any work) if it cannot start this run: another
        method, map size, layout (S, G, obstacles) or reward scheme, or none recorded."""
        if self.method != method:
            raise InputError(where, arg, f"{self.source} is a {self.method} learner, this run's "
                             f"method is {method}", f"pass method={self.method!r}, or an init "
                             f"trained with {method}")
        if self.n_states != n_states:
            raise InputError(where, arg, f"{self.source} was trained on a map of "
                             f"{self.n_states:,} cells, this scenario has {n_states:,}",
                             "use a learner trained on this scenario")
        if self.layout is None or self.rewards is None:
            raise InputError(where, arg, f"{self.source} does not record the scenario and "
                             "rewards it was trained on", "train it again with save=... "
                             "(rnhql train --save) and start from that")
        if self.layout != layout:
            raise InputError(where, arg, f"{self.source} was trained on another scenario "
                             f"(layout {self.layout}, this one {layout})",
                             "use a learner trained on this scenario (same map, S and G)")
        if self.rewards != rewards:
            raise InputError(where, arg, f"{self.source} learned under rewards "
                             f"{self.rewards!r}, this run has {rewards!r}",
                             "pass the rewards it was trained with (its values are in their "
                             "units)")


def _continued(state: dict | None, fallback: np.random.Generator) -> np.random.Generator:
    if state is None:
        return fallback
    g = np.random.default_rng()
    g.bit_generator.state = copy.deepcopy(state)
    return g


def carried_of_checkpoint(path: Path, n_states: int, geometry: Any) -> Carried:
    """A saved agent (``train(..., save=...)``, ``rnhql train --save``) as a warm start; a
    file of another format or size raises :class:`CheckpointError` naming it."""
    try:
        ck = load_checkpoint(path, None, None, geometry)  # its format, shapes and values
    except CheckpointError as original:
        try:  # another map's agent: say so by its size, when the file tells it
            got = n_states_of(load_checkpoint(path).state)
        except (CheckpointError, AttributeError, KeyError, ValueError):
            raise original from None
        if got != n_states:
            raise CheckpointError(f"{path}: was trained on a map of {got:,} cells, this "
                                  f"scenario has {n_states:,}; use an agent trained on this "
                                  "scenario") from None
        raise
    problem = ck.problem or {}
    world = problem.get("world", "grid")
    phase = {"world": world, "fidelity": problem.get("fidelity"), "episodes": ck.episodes,
             "env_steps": int(ck.env_steps),
             "wall_time_s": float(np.sum(ck.metrics.get("wall_time_s", ()))),
             "final_route_length": (int(ck.metrics["test_route_length"][-1])
                                    if len(ck.metrics.get("test_route_length", ())) else -1)}
    return Carried(ck.method, ck.config, ck.state, None, ck.rng_state, ck.start_rng_state,
                   phase, problem.get("layout"), n_states, str(path), problem.get("rewards"))


def phase_record(result: Any, world: str, fidelity: str | None) -> dict[str, Any]:
    """A finished phase in its own currency: episodes and moves (grid) or robot primitives
    and robot seconds (physics), wall time, and where its greedy route from S ended."""
    steps = np.asarray(result.steps)
    out: dict[str, Any] = {"world": world, "fidelity": fidelity, "episodes": int(steps.size),
                           "env_steps": int(steps.sum()),
                           "wall_time_s": float(np.sum(result.wall_time_s)),
                           "final_route_length": int(result.final_route_length)}
    sim = getattr(result, "world_extras", {}).get("sim_time_per_episode_s")
    if world == "physics" and sim is not None:
        out["robot_primitives"] = out["env_steps"]
        out["robot_seconds"] = round(float(np.sum(sim)), 4)
    return out


def carried_of(method: str, result: Any, learner_rng: np.random.Generator | None,
               start_rng: np.random.Generator | None, world: str, fidelity: str | None,
               layout: str | None, n_states: int, source: str,
               rewards: str | None = None) -> Carried:
    """What a finished run carries (``result``: a TrainResult, grid or physics)."""
    cfg = result.config
    plain = is_plain(cfg)
    agent = getattr(result, "agent", None)
    return Carried(method, cfg, None if plain else result.state,
                   agent.learner if plain else None,
                   None if learner_rng is None else learner_rng.bit_generator.state,
                   None if start_rng is None else start_rng.bit_generator.state,
                   phase_record(result, world, fidelity), layout, n_states, source, rewards)


def pretrain_in_grid(method: str, cfg: Any, model: Any, episodes: int, test_every: int,
                     learner_rng: np.random.Generator, start_rng: np.random.Generator,
                     observer: Any = None) -> Carried:
    """The grid phase of a pretrained run: ``episodes`` in the grid on the run's own learner
    and start streams (which continue into the rung's phase: common random numbers);
    ``observer``: a recording of the phase (it changes nothing about the run)."""
    result = train_grid(cfg, model, episodes, learner_rng, test_every, observer=observer,
                   start_rng=start_rng)
    c = carried_of(method, result, None, None, "grid", None, None, int(model.n_states),
                   "the grid phase")
    return c

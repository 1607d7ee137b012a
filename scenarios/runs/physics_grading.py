"""A physics run graded in the world it trained in.

At ``exact`` a primitive's outcome is a function of the cell and the action, so the
physics world is a deterministic model (:func:`sim.physics.models.transition.physics_model`: each
primitive driven once from each reachable cell centre), and a greedy test is a walk on
it, as on the grid. Above ``exact`` that model is the wrong world: a bump there means
"stay", so one bump is "no G", while in the run's own world the robot rests against the
surface and drives on. So above ``exact`` every test drives the greedy policy (one action
per cell, :func:`learning.compiled.readout.greedy_actions`) from S as rollouts at the run's
fidelity (:func:`sim.physics.models.rollouts.drive_policy`), each with its own noise stream,
common across methods (seeded by the run's seed and the test's episode):

* a periodic test: :data:`TEST_ROLLOUTS` rollouts of at most
  ``TEST_BUDGET_FACTOR`` x the exact optimum + :data:`TEST_BUDGET_SLACK` primitives (a
  longer drive is far from optimal whatever it does next, and a policy that loops would
  otherwise cost the full episode length ten times per test); its route length is the
  median number of primitives (a rollout that missed G counting as infinite; -1 when
  the median is), so "optimal" means at least half the drives took the fewest moves;
* the final policy: :data:`FINAL_ROLLOUTS` rollouts, reported as P(G) with a Wilson 95 %
  interval (50 drives bound a policy that never missed at P >= 0.93) and the mean and
  median primitives, contacts, bumps, metres and sim time (``final_policy`` in the
  record); ``physics_route_*`` describe rollout 0, one sample drawn on the map.

At ``exact`` the final policy is driven once (every drive is the same): the record is
the one it always was, plus the ``final_policy`` figures of that one drive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from learning.compiled.readout import greedy_actions
from learning.drivers.train import epsilon_route_lengths, greedy_test, shortest_fraction
from sim.physics.fidelity import Fidelity
from sim.physics.models.rollouts import (
    Rollouts,
    drive_epsilon_greedy,
    drive_policies,
    drive_policy,
    rollout_env,
)
from sim.physics.models.transition import physics_model
from sim.scenario import Scenario

TEST_ROLLOUTS = 10  # drives per periodic greedy test above exact
TEST_BUDGET_FACTOR = 3  # a periodic test's drive ends after this x the exact optimum ...
TEST_BUDGET_SLACK = 20  # ... + this many primitives (at most the episode length)
FINAL_ROLLOUTS = 50  # drives of the final policy above exact
FINAL_BATCH = 16  # final policies above exact driven together, one env [policies]
FINAL_TAG = 1 << 40  # the final policy's rollout streams (periodic tests use the episode)
EPSILON_TAG = (1 << 40) + 1  # the epsilon-greedy test's rollout streams
EPSILON_ROLLOUTS = 20  # as learning.drivers.train.epsilon_route_lengths


@dataclass
class FinalGrade:
    """The final policy's figures: what the record and the recording read."""

    length: int  # exact: the greedy route's moves; above: median primitives; -1: no G
    route: list[int]  # the cells of the drive shown (S first)
    optimal_action_fraction: float
    extras: dict[str, Any] = field(default_factory=dict)
    rollouts: Rollouts | None = None


def median_length(r: Rollouts) -> int:
    """Median primitives to G as a whole number of moves (rounded up), -1 when infinite."""
    med = r.median_primitives()
    return -1 if not math.isfinite(med) else math.ceil(med)


def route_extras(r: Rollouts) -> dict[str, Any]:
    """``physics_route_*``: rollout 0, the drive drawn on the map."""
    reached = bool(r.reached[0])
    return {"physics_route_length": int(r.primitives[0]) if reached else -1,
            "physics_route_xy": np.round(r.path[::2, :2], 3).tolist(),
            "physics_route_metres": round(float(r.metres[0]), 4),
            "physics_route_contacts": int(r.contacts[0]),
            "physics_route_sim_time_s": round(float(r.sim_time_s[0]), 4)}


class Grader:
    """Greedy tests and the final grade of physics runs on one scenario and fidelity."""

    def __init__(self, sc: Scenario, fidelity: Fidelity | None = None) -> None:
        self.scenario = sc
        self.fidelity = fidelity or Fidelity()
        self.exact = physics_model(sc)  # the disc's own moves at exact (the yardstick there)
        self._envs: dict[tuple[int, bool], Any] = {}  # rollout envs, built once

    def _env(self, n: int, trajectories: bool) -> Any:
        key = (n, trajectories)
        if key not in self._envs:
            self._envs[key] = rollout_env(self.scenario, n, self.fidelity,
                                          trajectories=trajectories)
        return self._envs[key]

    @property
    def in_rollouts(self) -> bool:
        return not self.fidelity.is_exact

    def drive(self, st, n: int, seed: int, tag: int, **kw: Any) -> Rollouts:
        env = self._env(n, kw.get("measure_metres", False) or kw.get("keep_path", False))
        return drive_policy(self.scenario, greedy_actions(st), self.fidelity, n, seed, tag,
                            env=env, **kw)

    def test(self, st, seed: int, episode: int) -> tuple[int, list[int]]:
        """(route length or -1, cells of the route shown) of a periodic greedy test."""
        if not self.in_rollouts:
            return greedy_test(st, self.exact)
        return self.tests([greedy_actions(st)], [seed], [episode])[0]

    def tests(self, tables: list[np.ndarray], seeds: list[int], episodes: list[int]
              ) -> list[tuple[int, list[int]]]:
        """:meth:`test` above ``exact`` of several greedy policies (``int[nS]`` each, the
        policy when its test fell due) at once: one env, one compiled call per primitive
        for all their drives (:func:`sim.physics.models.rollouts.drive_policies`), each test's
        drives the same as alone. A test reads its median and rollout 0 only, so a drive
        that can no longer change the median is cut short (``median_only``: a policy that
        cannot reach G costs half its drives)."""
        opt = max(self.exact.optimal_route_length, 0)
        budget = min(self.scenario.steps_per_episode,
                     TEST_BUDGET_FACTOR * opt + TEST_BUDGET_SLACK)
        env = self._env(len(tables) * TEST_ROLLOUTS, False)
        rs = drive_policies(self.scenario, tables, self.fidelity, TEST_ROLLOUTS, seeds,
                            episodes, budget, keep_routes=True, env=env, median_only=True)
        return [(median_length(r), r.routes[0]) for r in rs]

    def final(self, st, seed: int) -> FinalGrade:
        frac = shortest_fraction(st, self.exact)
        if not self.in_rollouts:
            length, route = greedy_test(st, self.exact)
            r = self.drive(st, 1, 0, 0, measure_metres=True, keep_path=True)
            return FinalGrade(length, route, frac,
                              {**route_extras(r), "final_policy": r.summary()}, r)
        r = self.drive(st, FINAL_ROLLOUTS, seed, FINAL_TAG, measure_metres=True,
                       keep_routes=True, keep_path=True)
        return self._graded(st, r)

    def finals(self, states: list[Any], seeds: list[int]) -> list[FinalGrade]:
        """:meth:`final` of several runs' learner states; above ``exact`` their rollouts are
        driven :data:`FINAL_BATCH` policies at a time in one env (each policy's drives
        equal to its own: :func:`sim.physics.models.rollouts.drive_policies`)."""
        if not self.in_rollouts:
            return [self.final(st, seed) for st, seed in zip(states, seeds, strict=True)]
        out: list[FinalGrade] = []
        for b in range(0, len(states), FINAL_BATCH):
            sts, sds = states[b:b + FINAL_BATCH], seeds[b:b + FINAL_BATCH]
            env = self._env(len(sts) * FINAL_ROLLOUTS, True)
            rs = drive_policies(self.scenario, [greedy_actions(st) for st in sts],
                                self.fidelity, FINAL_ROLLOUTS, list(sds), [FINAL_TAG] * len(sts),
                                measure_metres=True, keep_routes=True, keep_path=True, env=env)
            out += [self._graded(st, r) for st, r in zip(sts, rs, strict=True)]
        return out

    def _graded(self, st: Any, r: Rollouts) -> FinalGrade:
        """The final grade of a policy from its rollouts (above ``exact``)."""
        length = median_length(r)
        shown = next((k for k in range(r.n) if r.reached[k]), 0)
        return FinalGrade(length, r.routes[shown], shortest_fraction(st, self.exact),
                          {**route_extras(r), "final_policy": r.summary()}, r)

    def epsilon_routes(self, st, eps: float, rng: np.random.Generator) -> np.ndarray:
        """The paper's epsilon-greedy test from S: route lengths (-1: G missed)."""
        if not self.in_rollouts:
            return epsilon_route_lengths(st, self.exact, eps, rng)
        r = drive_epsilon_greedy(self.scenario, greedy_actions(st), eps, rng, self.fidelity,
                                 EPSILON_ROLLOUTS, int(rng.integers(1 << 31)), EPSILON_TAG)
        return np.where(r.reached, r.primitives, -1)


def final_policy_label(fidelity: Fidelity, r: Rollouts | None, length: int) -> str:
    """What a recording writes beside the final policy's drive."""
    if r is None:
        return "final route: no G" if length < 0 else f"final route: {length} moves"
    lo, hi = r.p_goal_interval
    mean = r.primitives[r.reached].mean() if r.reached.any() else float("nan")
    return (f"final policy at {fidelity.label}: P(G) {r.p_goal:.2f} [{lo:.2f}, {hi:.2f}], "
            f"{mean:.1f} primitives, {r.contacts.mean():.1f} contacts ({r.n} drives)")

"""What a reward scheme asks of a learner, computed exactly by value iteration.

For a scenario, a scheme (goal / bump / free step) and a discount gamma:

- ``v_star_s``: V*(S), the value of the optimal route from S;
- ``v_never_s``: the best value from S of a policy that never enters G (every
  move into G forbidden), i.e. what wandering forever is worth;
- ``gap``: V*(S) - V_never(S): how much reaching G is worth over wandering;
- ``action_gap_min`` / ``action_gap_median``: along the optimal route, Q* of
  the best action minus Q* of the best strictly worse one (equally short
  alternatives are both optimal): how precisely a learner must estimate values
  to pick an optimal move at every step;
- ``goal_at_s``: the goal reward discounted to S, goal * gamma^(d - 1).

None of these numbers is typed by hand: reports quote them from here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from sim.grid import TabularModel, build_model
from sim.grid.planning import bfs_route, value_iteration
from sim.scenario import Rewards, Scenario


@dataclass(frozen=True)
class RewardFacts:
    scheme: str
    gamma: float
    optimal_route_length: int  # BFS moves S -> G
    v_star_s: float
    v_never_s: float
    gap: float
    action_gap_min: float
    action_gap_median: float
    goal_at_s: float


def with_rewards(sc: Scenario, rewards: Rewards) -> tuple[Scenario, TabularModel]:
    sc2 = dataclasses.replace(sc, rewards=rewards)
    return sc2, build_model(sc2)


def never_reaching_goal_value(model: TabularModel, gamma: float) -> np.ndarray:
    """V of the best policy that never enters G: moves into G are forbidden.

    Value iteration on the same MDP with those actions removed (-inf), from V = 0.
    """
    into_goal = model.terminal[model.next_state]
    v = np.zeros(model.next_state.shape[0])
    for _ in range(100_000):
        q = model.reward + gamma * v[model.next_state]
        q[into_goal] = -np.inf
        v_new = np.where(model.terminal, 0.0, q.max(axis=1))
        v_new[~np.isfinite(v_new)] = 0.0  # a state whose every move enters G
        if np.max(np.abs(v_new - v)) < 1e-10:
            return v_new
        v = v_new
    return v


def reward_facts(sc: Scenario, scheme: str, rewards: Rewards, gamma: float) -> RewardFacts:
    _, model = with_rewards(sc, rewards)
    v, q = value_iteration(model.next_state, model.reward, model.terminal, gamma)
    never = never_reaching_goal_value(model, gamma)
    route = bfs_route(model.next_state, model.distance_to_goal, model.start)
    gaps = []
    for s in route[:-1]:  # best action vs the best *suboptimal* one (ties are both optimal)
        best = q[s].max()
        worse = q[s][q[s] < best - 1e-12 * max(1.0, abs(best))]
        if worse.size:
            gaps.append(float(best - worse.max()))
    d = len(route) - 1
    s0 = model.start
    return RewardFacts(scheme=scheme, gamma=gamma, optimal_route_length=d,
                       v_star_s=float(v[s0]), v_never_s=float(never[s0]),
                       gap=float(v[s0] - never[s0]),
                       action_gap_min=float(min(gaps)) if gaps else 0.0,
                       action_gap_median=float(np.median(gaps)) if gaps else 0.0,
                       goal_at_s=float(rewards.goal * gamma ** (d - 1)))


def facts_markdown(rows: list[RewardFacts]) -> str:
    lines = ["| scheme | gamma | V*(S) | V never reaching G | gap | action gap on the route: "
             "min / median | goal discounted to S |", "|---|---|---|---|---|---|---|"]
    for f in rows:
        lines.append(f"| {f.scheme} | {f.gamma:g} | {f.v_star_s:.4g} | {f.v_never_s:.4g} | "
                     f"{f.gap:.3g} | {f.action_gap_min:.3g} / {f.action_gap_median:.3g} | "
                     f"{f.goal_at_s:.3g} |")
    return "\n".join(lines) + "\n"

"""Model learners in a world where a free move fails now and then (issue: learners that
survive a stochastic world; :mod:`learning.parts.move_model`, :mod:`learning.methods.haql`).

The hand-made case: a 7 x 5 grid, a wall at x = 3 with a door at (3, 1). S = (0, 1),
G = (6, 1): 6 moves through the door, 12 around the wall's top end. The move into
the door works the first time and then fails (the agent stays put, bump reward)
with probability 0.3, so going through costs 1 / 0.7 = 1.43 attempts in
expectation and is still optimal. A learner that takes a move that failed once
for a wall goes round (HAQL did, before its most-likely-outcome rule). (Were the
first attempt to fail, the door would look exactly like a wall; finding it again
is then up to exploration.)
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from learning import METHODS, geometry_of
from learning.drivers.agent import make_agent
from learning.drivers.train import greedy_test
from learning.parts.move_model import (
    never_worked,
    new_move_model,
    observe_outcome,
    replay_draws_failure,
)
from sim.grid.actions import ACTION_DELTAS

NX, NY = 7, 5
WALL = {(3, 0), (3, 2), (3, 3)}
S, G = (0, 1), (6, 1)
P_FAIL = 0.3
GOAL_R, BUMP_R = 100.0, -1.0


def sid(x: int, y: int) -> int:
    return y * NX + x


DOOR = (sid(2, 1), 3)  # (state, action "right") into the door


def door_world():
    cells = [(x, y) for y in range(NY) for x in range(NX)]
    n = len(cells)
    nxt = np.zeros((n, 4), dtype=np.int32)
    rew = np.zeros((n, 4))
    for s, (x, y) in enumerate(cells):
        for a, (dx, dy) in enumerate(ACTION_DELTAS):
            tx, ty = x + dx, y + dy
            ok = 0 <= tx < NX and 0 <= ty < NY and (tx, ty) not in WALL and (x, y) not in WALL
            nxt[s, a] = sid(tx, ty) if ok else s
            rew[s, a] = (GOAL_R if (tx, ty) == G else 0.0) if ok else BUMP_R
    g = sid(*G)
    nxt[g], rew[g] = g, 0.0
    free = np.array([s for s, c in enumerate(cells) if c not in WALL and c != G], np.int32)
    return SimpleNamespace(next_state=nxt, reward=rew, terminal=np.arange(n) == g,
                           coords=np.array([[x + 0.5, y + 0.5] for x, y in cells]),
                           start_states=free, start=sid(*S), goal=g, cell_size_m=1.0,
                           bounds_m=(0.0, 0.0, float(NX), float(NY)), max_steps=60)


def train(method: str, seed: int, episodes: int = 500):
    m = door_world()
    agent = make_agent(METHODS[method](), geometry_of(m), np.random.default_rng(seed))
    world_rng = np.random.default_rng(1000 + seed)
    fails = tries = 0
    for _ in range(episodes):
        s = int(world_rng.choice(m.start_states))
        agent.begin_episode(s)
        for _t in range(m.max_steps):
            a = agent.act(s)
            s2, r = int(m.next_state[s, a]), float(m.reward[s, a])
            if (s, a) == DOOR:
                tries += 1
                if tries > 1 and world_rng.random() < P_FAIL:
                    s2, r = s, BUMP_R
                    fails += 1
            term = bool(m.terminal[s2])
            agent.update(s, a, r, s2, term, False)
            s = s2
            if term:
                break
        agent.end_episode()
    return agent, m, fails


@pytest.mark.parametrize("method", ["rnh-ql+", "haql"])
def test_model_learners_keep_the_route_through_a_move_that_sometimes_fails(method):
    """(Dyna-Q is left out: with Q = 0 untried moves it often never tries the door cell's
    way on in these budgets, stochastic door or not; its model's replay is tested below.)
    HAQL gets more episodes: when the door's second and third attempts both fail (p =
    0.09) bumps are its most likely outcome until exploration tries it again."""
    for seed in range(5):
        agent, m, fails = train(method, seed, 500 if method == "rnh-ql+" else 1000)
        assert fails > 0  # the door did fail during training
        length, _ = greedy_test(agent.state, m)
        assert length == 6, (method, seed, length)


def test_optimistic_model_keeps_a_door_that_failed_free_and_a_wall_a_wall():
    agent, _m, fails = train("rnh-ql+", 0)
    model = agent.state.model
    s, a = DOOR
    assert fails > 0
    assert not never_worked(model.successor, model.works, s, a)
    assert model.works[s, a] > 0 and model.fails[s, a] > 0
    assert model.successor[s, a] == sid(3, 1)  # the successor stays the door cell through failures
    wall = (sid(2, 2), 3)  # (2, 2) -> (3, 2) is a wall
    if model.successor[wall] >= 0:  # tried
        assert never_worked(model.successor, model.works, *wall)


def test_haql_blocks_a_move_while_bumps_are_its_most_likely_outcome():
    from learning.drivers.state import init_state
    from learning.methods.haql import HAQL, observe

    st = init_state(HAQL(), geometry_of(door_world()), np.random.default_rng(0))
    fs = st.free

    def see(s, a, s2):
        # a stay is a bump, an arrival here is clean (no grazing in this test)
        observe(st.balance, st.pi_h, fs.neighbour, fs.blocked, fs.distance, fs.queue,
                fs.goal[0], s, a, s2, False, s2 != s, st.cost, st.cost_ok)

    s, a = DOOR
    door = sid(3, 1)
    assert st.pi_h[s] == a  # the free-space heuristic heads through the door
    see(s, a, s)  # a bump: blocked, pi_H goes round
    assert fs.blocked[s, a] and st.pi_h[s] != a
    see(s, a, sid(2, 0))  # drifted elsewhere: no news
    assert fs.blocked[s, a]
    see(s, a, door)  # got through: as often as it bumped
    assert not fs.blocked[s, a] and st.pi_h[s] == a
    see(s, a, s)  # one more bump: blocked again
    assert st.pi_h[s] != a


def test_move_model_replays_failures_at_the_rate_seen():
    m = new_move_model(3, 4)

    def see(s, a, r, s2, worked):
        observe_outcome(m.successor, m.to_goal, m.reward, m.works, m.fails, m.r_fail, s, a, r,
                        s2, False, worked)

    s, a, s2 = 0, 3, 1
    see(s, a, BUMP_R, s, False)
    assert never_worked(m.successor, m.works, s, a) and m.successor[s, a] == s
    for _ in range(3):
        see(s, a, 0.0, s2, True)
    see(s, a, BUMP_R, s, False)
    assert not never_worked(m.successor, m.works, s, a)
    assert m.successor[s, a] == s2 and m.reward[s, a] == 0.0  # the successor survives failure
    rng = np.random.default_rng(0)
    rate = np.mean([replay_draws_failure(m.works[s, a], m.fails[s, a], rng)
                    for _ in range(20000)])
    assert rate == pytest.approx(2 / 5, abs=0.015)  # 2 failures, 3 works
    # a pair seen only to work never draws (deterministic worlds: the draws of before)
    see(1, 0, 0.0, 2, True)
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    assert not replay_draws_failure(m.works[1, 0], m.fails[1, 0], rng_a)
    assert rng_a.random() == rng_b.random()

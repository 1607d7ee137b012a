"""Each update rule against updates computed by hand on a 1 x 3 corridor.

Corridor: states 0 1 2 (x = 0.5, 1.5, 2.5 m), goal 2. ``right`` moves (+1, or
+100 into the goal, terminating); ``left`` from 1 moves back (+1); every other
move is a bump (-1, stay). gamma = 0.95, alpha = 0.1 throughout.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from learning import HAQL, PFHRL, RNHQL, RNQL, STQL, DynaQ, QLambda, QOpt, SarsaRS
from learning.drivers.agent import make_agent
from learning.geometry import Geometry
from learning.methods.haql import heuristic_actions
from learning.methods.pfh_rl import pfh_potential
from learning.methods.sarsa_rs import abstract_states
from learning.parts.mlp import add_gradient, net, normalised_inputs
from learning.parts.rbf import rbf_features, td_lambda
from learning.parts.tabular import argmax_first, argmax_random, eps_greedy, sarsa

G, A = 0.95, 0.1
UP, DOWN, LEFT, RIGHT = 0, 1, 2, 3


def corridor():
    nxt = np.array([[0, 0, 0, 1], [1, 1, 0, 2], [2, 2, 2, 2]], dtype=np.int32)
    rew = np.array([[-1, -1, -1, 1], [-1, -1, 1, 100], [0, 0, 0, 0]], dtype=np.float64)
    coords = np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 0.5]])
    return SimpleNamespace(next_state=nxt, reward=rew, terminal=np.array([False, False, True]),
                           coords=coords, start_states=np.array([0, 1], dtype=np.int32),
                           start=0, goal=2, distance_to_goal=np.array([2, 1, 0], dtype=np.int32),
                           cell_size_m=1.0, bounds_m=(0.0, 0.0, 3.0, 1.0), max_steps=20)


def geom(start_states=(0, 1)):
    m = corridor()
    return Geometry(m.coords, 2, m.bounds_m, 3, 4, 1.0, np.array(start_states, dtype=np.int32))


def agent(cfg, seed=0):
    return make_agent(cfg, geom(), np.random.default_rng(seed))


# ---------------------------------------------------------------- action choice
def test_argmax_first_and_random_ties():
    q = np.array([[1.0, 3.0, 3.0, 0.0]])
    assert argmax_first(q, 0) == 1
    rng = np.random.default_rng(1)
    picks = {argmax_random(q, 0, rng) for _ in range(200)}
    assert picks == {1, 2}


def test_eps_greedy_draw_order_matches_numpy():
    """One random(); then integers(0, nA) when exploring, integers(0, n_ties) on a tie."""
    q = np.array([[0.0, 2.0, 2.0, 1.0]])
    a, b = np.random.default_rng(5), np.random.default_rng(5)
    for _ in range(300):
        got = eps_greedy(q, 0, 0.3, a)
        if b.random() < 0.3:
            want = b.integers(0, 4)
        else:
            want = (1, 2)[b.integers(0, 2)]
        assert got == want
    assert a.bit_generator.state == b.bit_generator.state


def test_unique_greedy_draws_one_number():
    q = np.array([[0.0, 2.0, 1.0, 1.0]])
    a, b = np.random.default_rng(9), np.random.default_rng(9)
    assert eps_greedy(q, 0, 0.0, a) == 1
    b.random()
    assert a.bit_generator.state == b.bit_generator.state


# ---------------------------------------------------------------- Q-learning family
def test_q_learning_terminal_and_bootstrap():
    ag = agent(STQL())
    ag.update(1, RIGHT, 100.0, 2, True, False)
    assert ag.state.q[1, RIGHT] == pytest.approx(10.0)
    ag.update(0, RIGHT, 1.0, 1, False, False)
    assert ag.state.q[0, RIGHT] == pytest.approx(A * (1 + G * 10.0))


def test_truncation_still_bootstraps():
    ag = agent(STQL())
    ag.state.q[1, RIGHT] = 10.0
    ag.update(0, RIGHT, 1.0, 1, False, True)
    assert ag.state.q[0, RIGHT] == pytest.approx(A * (1 + G * 10.0))


def test_q_opt_starts_at_goal_reward():
    assert np.all(agent(QOpt()).state.q == 100.0)


def test_q_lambda_traces_and_cut():
    ag = agent(QLambda())
    ag.begin_episode(0)
    ag.update(0, RIGHT, 1.0, 1, False, False)
    assert ag.state.q[0, RIGHT] == pytest.approx(0.1)
    ag.update(1, RIGHT, 100.0, 2, True, False)
    assert ag.state.q[1, RIGHT] == pytest.approx(10.0)
    assert ag.state.q[0, RIGHT] == pytest.approx(0.1 + A * 100.0 * G * 0.85)
    ag.end_episode()
    ag.begin_episode(0)
    ag.update(0, RIGHT, 1.0, 1, False, False)  # greedy: trace 1
    q01 = ag.state.q[0, RIGHT]
    ag.update(1, UP, -1.0, 1, False, False)  # non-greedy (Q[1, right] = 10): cut
    assert ag.state.q[0, RIGHT] == q01
    assert ag.state.q[1, UP] == pytest.approx(A * (-1 + G * 10.0))


def test_sarsa_update():
    q = np.zeros((3, 4))
    q[1, LEFT] = 10.0
    sarsa(q, 0, RIGHT, 1.0, 1, LEFT, False, A, G, 0.5)
    assert q[0, RIGHT] == pytest.approx(A * (1 + 0.5 + G * 10.0))


def test_dyna_plans_on_the_learned_model():
    ag = agent(DynaQ())
    ag.update(0, RIGHT, 1.0, 1, False, False)  # 1 real + 5 simulated updates of one pair
    assert ag.state.q[0, RIGHT] == pytest.approx(1 - 0.9 ** 6)
    assert ag.state.model.successor[0, RIGHT] == 1 and ag.state.model.reward[0, RIGHT] == 1.0
    assert ag.state.model.n_seen[0] == 1


# ---------------------------------------------------------------- heuristics and shaping
def test_heuristic_actions_and_haql_choice():
    g3 = Geometry(np.array([[x + 0.5, y + 0.5] for y in range(3) for x in range(3)]), 5,
                  (0.0, 0.0, 3.0, 3.0), 9, 4)
    pi = heuristic_actions(g3)
    assert pi[0] == RIGHT  # (0,0) -> G (2,1): 2 cells in x, 1 in y
    assert pi[2] == UP  # (2,0): straight up
    assert pi[8] == DOWN  # (2,2)
    ag = agent(HAQL())
    assert ag.greedy_action(0) == RIGHT  # Q ties at 0: the heuristic move wins
    ag.state.q[0] = [5.0, 0.0, 0.0, 1.0]  # 1 + (5 - 1 + eta) > 5
    assert ag.greedy_action(0) == RIGHT
    ag.update(0, RIGHT, 1.0, 1, False, False)  # Q-learning, no heuristic in the update
    assert ag.state.q[0, RIGHT] == pytest.approx(1.0 + A * (1.0 - 1.0))


def test_pfh_static_shaping():
    phi = pfh_potential(geom(), 2.0)
    assert phi.tolist() == [-4.0, -2.0, 0.0]
    ag = agent(PFHRL(scale=2.0))
    ag.update(0, RIGHT, 1.0, 1, False, False)
    assert ag.state.q[0, RIGHT] == pytest.approx(A * (1 + G * -2.0 + 4.0))
    ag.update(1, RIGHT, 100.0, 2, True, False)  # Phi(goal) = 0
    assert ag.state.q[1, RIGHT] == pytest.approx(A * (100 + 2.0))


def test_sarsa_rs_smdp_update():
    z, n_z = abstract_states(geom(), 2)
    assert z.tolist() == [0, 0, 1] and n_z == 2
    ag = agent(SarsaRS(block=2, eps=0.0))
    ag.begin_episode(0)
    assert ag.act(0) in (0, 1, 2, 3)
    ag.update(0, RIGHT, 1.0, 1, False, False)  # same abstract state: no V update yet
    assert ag.state.v.tolist() == [0.0, 0.0]
    ag.update(1, RIGHT, 100.0, 2, True, False)  # left z=0 after 2 steps, R = 1 + 0.95*100
    assert ag.state.v[0] == pytest.approx(0.1 * (1 + G * 100))
    ag.end_episode()
    ag.begin_episode(0)
    q_before = ag.state.q.copy()
    ag.update(0, RIGHT, 1.0, 1, False, False)  # F = gamma*Phi(z0) - Phi(z0)
    a2 = ag.state.pending[0]
    f = (G - 1) * 0.1 * (1 + G * 100)  # omega = 1, V(z0) after the first episode
    want = q_before[0, RIGHT] + A * (1 + f + G * q_before[1, a2] - q_before[0, RIGHT])
    assert ag.state.q[0, RIGHT] == pytest.approx(want)
    assert ag.act(1) == a2  # the action drawn in the update is the one taken next


# ---------------------------------------------------------------- RBF V_NN and RNH-QL
def test_rbf_features_peak_at_centres():
    phi = rbf_features(np.array([[0.5, 0.5], [1.0, 0.5]]), (0.0, 0.0, 3.0, 1.0), 3)
    assert phi.shape == (2, 9)
    assert phi[0].max() == pytest.approx(1.0)  # on a centre
    assert np.all(phi > 0) and np.all(phi <= 1)


def test_td_lambda_greedy_and_cut():
    phi = np.array([[1.0, 0.5], [0.2, 1.0]])
    w, e = np.zeros(2), np.zeros(2)
    td_lambda(w, e, phi, 0, 1.0, 0.5, True, G, 0.85, 0.1)
    assert e.tolist() == [1.0, 0.5]
    np.testing.assert_allclose(w, 0.1 * (1 + G * 0.5) * phi[0])
    w1 = w.copy()
    td_lambda(w, e, phi, 1, 1.0, 0.0, False, G, 0.85, 0.1)
    assert e.tolist() == [0.0, 0.0] and np.array_equal(w, w1)


def test_rnh_ql_caches_potential_on_entry():
    g = geom()
    ag = make_agent(RNHQL(k=3, warmup_episodes=0), g, np.random.default_rng(0))
    st = ag.state
    st.w[:] = np.linspace(1.0, 9.0, 9)
    phi, step = st.phi, st.step_v[0]
    w0 = st.w.copy()
    v0 = phi @ w0
    ag.begin_episode(0)
    ag.update(0, RIGHT, 1.0, 1, False, False)
    w1 = w0 + step * (1 + G * v0[1] - v0[0]) * phi[0]
    np.testing.assert_allclose(st.w, w1)
    assert st.q[0, RIGHT] == pytest.approx(A * (1 + G * v0[1] - v0[0]))
    ag.update(1, RIGHT, 100.0, 2, True, False)
    # Phi(1) is the value cached on entering 1 (weights w0), Phi(goal) = 0
    assert st.q[1, RIGHT] == pytest.approx(A * (100 + 0 - v0[1]))
    e = G * 0.85 * phi[0] + phi[1]
    np.testing.assert_allclose(st.w, w1 + step * (100 - phi[1] @ w1) * e)
    ag.end_episode()
    assert ag.last_shaping[0] == pytest.approx(((G * v0[1] - v0[0]) - v0[1]) / 2)


def test_rnh_ql_warmup_and_freeze():
    ag = make_agent(RNHQL(k=3, warmup_episodes=1, freeze_after_episodes=1), geom(),
                    np.random.default_rng(0))
    ag.begin_episode(0)
    ag.update(0, RIGHT, 1.0, 1, False, False)
    assert ag.state.q[0, RIGHT] == pytest.approx(0.1)  # no shaping in episode 0
    assert np.any(ag.state.w != 0)  # V_NN trained from the first episode
    ag.end_episode()
    assert ag.last_shaping == (0.0, 0.0)  # episode 0 had no shaping term
    w = ag.state.w.copy()
    phi = ag.state.phi @ w  # Phi = V_NN, frozen from here on
    f = G * phi[1] - phi[0]
    assert abs(f) > 1e-6  # a real shaping term, not a vacuous check
    q_before = ag.state.q[0, RIGHT]
    ag.begin_episode(0)
    ag.update(0, RIGHT, 1.0, 1, False, False)
    assert np.array_equal(ag.state.w, w)  # frozen from episode 1
    # episode 1 is past the warm-up: the Q update adds F = gamma Phi(s') - Phi(s)
    assert ag.state.q[0, RIGHT] == pytest.approx(q_before + A * (1.0 + f + G * 0.0 - q_before))
    ag.end_episode()
    assert ag.state.tally.n_shaped[0] == 1
    assert ag.last_shaping == pytest.approx((f, 0.0))


# ---------------------------------------------------------------- RN-QL nets
def test_net_gradient_matches_finite_differences():
    rng = np.random.default_rng(3)
    w = rng.uniform(-1, 1, 4 * 41)
    x = np.array([[0.3, 0.7]])
    g = np.zeros_like(w)
    add_gradient(w, x, 0, 2, 10, g)
    num = np.zeros_like(w)
    for i in range(w.size):
        d = np.zeros_like(w)
        d[i] = 1e-6
        num[i] = (net(w + d, x, 0, 2, 10) - net(w - d, x, 0, 2, 10)) / 2e-6
    np.testing.assert_allclose(g, num, atol=1e-7)
    assert np.all(g[:2 * 41] == 0) and np.all(g[3 * 41:] == 0)  # only net 2


def test_rn_ql_first_update_is_one_gradient_step():
    ag = agent(RNQL(), seed=4)
    w0 = ag.state.w.copy()
    x = normalised_inputs(corridor().coords, (0.0, 0.0, 3.0, 1.0))
    q0 = [net(w0, x, 0, b, 10) for b in range(4)]
    a = int(np.argmax(q0))  # greedy: the trace is kept (it is 0 anyway)
    m1 = max(net(w0, x, 1, b, 10) for b in range(4))
    delta = 1.0 / 100.0 + G * m1 - q0[a]
    grad = np.zeros_like(w0)
    add_gradient(w0, x, 0, a, 10, grad)
    ag.begin_episode(0)
    ag.update(0, a, 1.0, 1, False, False)
    np.testing.assert_allclose(ag.state.w, w0 + A * delta * grad, rtol=1e-12)
    np.testing.assert_allclose(ag.state.e, grad)


def test_rbf_lattice_by_spacing_follows_the_map():
    from learning.parts.rbf import lattice_size

    assert lattice_size((0.0, 0.0, 50.0, 50.0), 10) == (10, 10)  # the paper's, by count
    assert lattice_size((0.0, 0.0, 512.0, 256.0), 10, spacing_m=8.0) == (64, 32)
    cfg = RNHQL(spacing_m=1.0)
    ag = make_agent(cfg, geom(), np.random.default_rng(0))  # a 3 x 1 m corridor
    assert ag.state.phi.shape == (3, 3 * 1)

"""RNH-QL+: the optimistic model, look-ahead, known routes, the Dyna-Q limit; and the
ablation's sparse features and leak-free supports."""

from __future__ import annotations

import numpy as np
import pytest

from learning import METHODS, RNHQLPlus, RNHQLPlusAblation, geometry_of, train_tabular
from learning.methods.rnh_ql_plus_ablation.features import sparse_features
from tests.conftest import corridor_moves


def test_sparse_features_match_dense_within_cutoff(paper50_model):
    geom = geometry_of(paper50_model)
    dense, ids_d, k = sparse_features(geom, 5, 10, 1.0, 0.0, False)
    sparse, ids, k2 = sparse_features(geom, 5, 10, 1.0, 2.0, False)
    assert k == k2 == 100 and sparse.shape[1] < dense.shape[1]
    full = np.zeros((geom.n_states, k))
    np.put_along_axis(full, ids_d.astype(np.int64), dense, axis=1)
    part = np.zeros((geom.n_states, k))
    np.add.at(part, (np.arange(geom.n_states)[:, None], ids.astype(np.int64)), sparse)
    kept = part > 0
    np.testing.assert_allclose(part[kept], full[kept])
    assert np.all(full[~kept] <= np.exp(-0.5 * 4.0) + 1e-12)  # only beyond 2 widths dropped


def test_scale_zero_is_dyna_q(paper50_model):
    a = train_tabular(RNHQLPlus(shaping_scale=0.0, lookahead=0, n_planning=5), paper50_model, 30,
                      np.random.default_rng(3))
    b = train_tabular(METHODS["dyna-q"](), paper50_model, 30, np.random.default_rng(3))
    np.testing.assert_array_equal(a.state.q, b.state.q)
    np.testing.assert_array_equal(a.steps, b.steps)


def test_leak_free_supports_only_grow_along_seen_moves(paper50_model):
    r = train_tabular(RNHQLPlusAblation(leak_free=1), paper50_model, 20, np.random.default_rng(0))
    feat = r.state.feat
    on = feat.on > 0
    assert on.any() and np.all(feat.on[on] == feat.base[on])
    successor = r.state.model.successor
    visited = (successor >= 0).any(axis=1)
    # a cell with a switched-on feature has been visited or is the end of a seen move
    ends = np.zeros_like(visited)
    seen = successor[successor >= 0]
    ends[seen] = True
    assert np.all((visited | ends)[on.any(axis=1)])


def test_readout_potential_is_the_potential_the_rules_shape_with():
    """The recorder's potential heat map is Phi as the rules compute it: rnh-ql+'s (the
    optimistic model's value) and a network potential of the ablation's."""
    from learning.compiled.readout import potential
    from learning.methods.rnh_ql_plus_ablation.potential import potential as rule_potential
    from scenarios.runs.spec import load

    _, m = load("paper-40", None, None, "goal-only")
    st = train_tabular(RNHQLPlus(), m, 100, np.random.default_rng(0)).state
    default = potential(st)
    np.testing.assert_array_equal(default, st.par.scale * st.opt.y)
    # the default's potential: the goal reward next to G, 0 at G, gamma per move further
    assert default.max() == 100.0 and default[m.goal] == 0.0
    cfg = RNHQLPlusAblation(v_target=1, shaping_scale=0.25, rebase=1)
    st = train_tabular(cfg, m, 100, np.random.default_rng(0)).state
    ref = np.array([rule_potential(st.par, st.w, st.feat.on, st.feat.centre, st.opt.y, s)
                    for s in range(m.n_states)])
    np.testing.assert_allclose(potential(st), ref, atol=1e-12)
    assert np.abs(ref).max() > 0


def test_optimistic_distances_are_free_space_bfs_then_go_round_a_seen_bump():
    """Before any move the optimistic model is the empty arena: BFS distance = Manhattan
    distance to G; after a bump on the way, the BFS goes round it."""
    from learning.drivers.state import init_state
    from learning.parts.free_space import bfs_to_goal
    from scenarios.runs.spec import load

    _, m = load("paper-40", None, None, "goal-only")
    geom = geometry_of(m)
    st = init_state(RNHQLPlus(), geom, np.random.default_rng(0))
    dist = st.free.distance
    g = geom.cells[geom.goal]
    manhattan = np.abs(geom.cells - g).sum(axis=1)
    np.testing.assert_array_equal(dist, manhattan)
    # mark the move "right" from the cell left of G as failed: that cell must go round
    left = int(np.flatnonzero((geom.cells == g - [1, 0]).all(axis=1))[0])
    st.free.blocked[left, 3] = True
    bfs_to_goal(st.free)
    assert dist[left] == 3 and dist[geom.goal] == 0


def test_bfs_skipped_only_where_no_distance_changes_and_values_match_the_formula():
    """Walls of zigzag-50 revealed in a random order: where distances_change says a new wall
    changes nothing, a full BFS agrees bit for bit; the cache of y filled in BFS order
    equals the closed form state by state. Both branches are taken."""
    from learning.drivers.state import init_state
    from learning.methods.rnh_ql_plus.optimism import goal_reward, refresh_values
    from learning.parts.free_space import bfs_to_goal, distances_change
    from scenarios.runs.spec import load

    _, m = load("zigzag-50", None, None, "goal-only")
    geom = geometry_of(m)
    st = init_state(RNHQLPlus(), geom, np.random.default_rng(0))
    n_s, n_a = geom.n_states, 4
    fs = st.free
    walls = [(s, a) for s in range(n_s) for a in range(n_a)
             if m.next_state[s, a] == s and not m.terminal[s]]
    order = np.random.default_rng(1).permutation(len(walls))
    skipped = rerun = 0
    for i in order:
        s, a = walls[i]
        fs.blocked[s, a] = True
        if distances_change(fs.neighbour, fs.distance, fs.blocked, s, a):
            bfs_to_goal(fs)
            rerun += 1
        else:
            before = fs.distance.copy()
            bfs_to_goal(fs)
            np.testing.assert_array_equal(fs.distance, before)
            skipped += 1
    assert skipped > 0 and rerun > 0
    opt = st.opt
    opt.r_goal[0] = 100.0
    g = st.par.gamma
    refresh_values(opt.y, opt.stamp, opt.r_goal, opt.r_free, fs.distance, fs.queue, g)
    r_goal = goal_reward(opt.r_goal, opt.r_free, g)
    d = fs.distance
    want = np.array([0.0 if k <= 0 else g ** (k - 1) * r_goal for k in d])
    np.testing.assert_allclose(opt.y, want, rtol=1e-12)
    assert (d < 0).any() or d.max() > 1


def test_rnh_ql_plus_learns_zigzag_where_rnh_ql_does_not():
    """zigzag-50 (a 212-move route round large walls): the default rnh-ql+ finds the optimal
    route within 300 episodes; the paper's rnh-ql does not (goal-only rewards, seed 0)."""
    from scenarios.runs.spec import load

    _, m = load("zigzag-50", None, None, "goal-only")
    plus = train_tabular(RNHQLPlus(), m, 300, np.random.default_rng(0))
    assert plus.final_route_length == m.optimal_route_length == 212
    base = train_tabular(METHODS["rnh-ql"](), m, 300, np.random.default_rng(0))
    assert base.final_route_length != 212


def test_potential_falls_toward_an_unseen_goal_under_the_paper_rewards():
    """With +1 per free move and G not reached yet, Phi must still fall with the distance to
    G (the stand-in goal reward beats wandering forever); a stand-in of 1 made it rise."""
    from learning.compiled.readout import potential
    from learning.drivers.state import init_state
    from learning.methods.rnh_ql_plus.optimism import goal_reward
    from scenarios.runs.spec import load

    _, m = load("paper-40", None, None, "paper")
    geom = geometry_of(m)
    st = init_state(RNHQLPlus(), geom, np.random.default_rng(0))
    st.opt.r_free[0] = 1.0  # a free move seen, G not yet
    assert goal_reward(st.opt.r_goal, st.opt.r_free, 0.95) == 1.0 / (1.0 - 0.95) + 1.0
    phi = potential(st)
    dist = np.abs(geom.cells - geom.cells[geom.goal]).sum(axis=1)
    near, far = np.argmin(np.where(dist > 0, dist, 99)), np.argmax(dist)
    assert phi[near] > phi[far] > 1.0 / (1.0 - 0.95)  # both above wandering forever
    st.opt.r_free[0] = 0.0  # goal-only: the stand-in is 1, as before
    assert goal_reward(st.opt.r_goal, st.opt.r_free, 0.95) == 1.0 and potential(st)[near] == 1.0


def test_rnh_ql_plus_learns_paper_50_under_the_paper_rewards():
    """The paper's own rewards (+1 per free move): the optimal 80-move route, seed 0."""
    from scenarios.runs.spec import load

    _, m = load("paper-50", None, None, "paper")
    run = train_tabular(RNHQLPlus(), m, 1000, np.random.default_rng(0))
    assert run.final_route_length == m.optimal_route_length == 80


def test_optimistic_model_needs_a_discount():
    with pytest.raises(ValueError, match=r"RNHQLPlus\.gamma = 1\.0 must be < 1 .*rnh-ql\+ablation"):
        RNHQLPlus(gamma=1.0)
    with pytest.raises(ValueError,
                       match=r"RNHQLPlusAblation\.gamma = 1\.0 must be < 1 with v_target = 4"):
        RNHQLPlusAblation(gamma=1.0)
    assert RNHQLPlusAblation(gamma=1.0, v_target=0).gamma == 1.0


def test_known_routes_are_bfs_over_moves_seen_to_work():
    from learning.parts.known_routes import known_distances, known_move, new_known_routes

    # a 1 x 4 corridor 0-1-2-3, G = 3; actions: 0 up, 1 down, 2 left, 3 right
    nb = corridor_moves(4)
    works = np.zeros((4, 4), np.int32)
    fails = np.zeros((4, 4), np.int32)
    kr = new_known_routes(4)
    works[1, 3] = works[2, 3] = 1  # 1 -> 2 -> 3 seen to work, 0 -> 1 not yet
    known_distances(nb, works, fails, kr.distance, kr.queue, 3)
    assert kr.distance.tolist() == [-1, 2, 1, 0]
    assert known_move(nb, works, fails, kr.distance, 1) == 3
    assert known_move(nb, works, fails, kr.distance, 0) == -1
    works[0, 3] = 1
    known_distances(nb, works, fails, kr.distance, kr.queue, 3)
    assert kr.distance.tolist() == [3, 2, 1, 0]


def test_a_known_route_uses_moves_that_work_more_often_than_they_fail():
    """With noise a move can work and fail: it carries a route while clean arrivals
    outnumber failures, leaves it when they do not, and comes back (no single failure
    blocks it for ever, no single lucky pass opens it)."""
    from learning.parts.known_routes import known_distances, new_known_routes

    nb = np.full((3, 4), -1, np.int32)  # a 1 x 3 corridor 0-1-2, G = 2
    nb[0, 3], nb[1, 3], nb[1, 2], nb[2, 2] = 1, 2, 0, 1
    works = np.zeros((3, 4), np.int32)
    fails = np.zeros((3, 4), np.int32)
    kr = new_known_routes(3)
    works[1, 3] = 3
    works[0, 3], fails[0, 3] = 1, 1  # once through, once bumped: a tie is not reliable
    known_distances(nb, works, fails, kr.distance, kr.queue, 2)
    assert kr.distance.tolist() == [-1, 1, 0]
    works[0, 3] = 2
    known_distances(nb, works, fails, kr.distance, kr.queue, 2)
    assert kr.distance.tolist() == [2, 1, 0]
    fails[0, 3] = 5
    known_distances(nb, works, fails, kr.distance, kr.queue, 2)
    assert kr.distance.tolist() == [-1, 1, 0]


@pytest.mark.parametrize("seed", [0, 1])
def test_greedy_test_walks_moves_seen_to_work_once_s_has_a_known_route(paper50, seed):
    """known_route: the test route from a cell with a known route is a shortest route of
    moves that have worked, so its length is the known distance and never an untried wall
    (a fifth of the episodes start at S, so that S has a known route after 100)."""
    import dataclasses

    from learning.parts.known_routes import known_distances
    from sim.grid import build_model

    model = build_model(dataclasses.replace(paper50, s_start_share=0.2))
    r = train_tabular(RNHQLPlus(), model, 100, np.random.default_rng(seed))
    st = r.state
    d = st.known.distance.copy()
    known_distances(st.free.neighbour, st.model.works, st.model.fails, d,
                    st.known.queue.copy(), model.goal)
    assert d[model.start] > 0, "S has a known route"
    assert r.final_route_length == d[model.start]
    works = st.model.works
    nb = st.free.neighbour
    for s, s2 in zip(r.final_route[:-1], r.final_route[1:], strict=True):
        a = int(np.flatnonzero(nb[s] == s2)[0])
        assert works[s, a] > 0


def test_known_route_off_is_the_look_ahead_test_and_training_is_unchanged(paper50_model):
    on = train_tabular(RNHQLPlus(), paper50_model, 40, np.random.default_rng(5))
    off = train_tabular(RNHQLPlus(known_route=0), paper50_model, 40, np.random.default_rng(5))
    np.testing.assert_array_equal(on.state.q, off.state.q)  # the test never changes training
    np.testing.assert_array_equal(on.steps, off.steps)


def test_model_acting_heads_for_g_in_the_optimistic_model(paper50_model):
    """model_acting: the behaviour's greedy move goes to a neighbour one move
    nearer G in the optimistic model, tried or not, never a move it holds blocked, and
    equal moves are drawn (not the lowest index)."""
    from learning.methods.rnh_ql_plus.rules import act

    r = train_tabular(RNHQLPlus(model_acting=1, eps=0.0), paper50_model, 20,
                      np.random.default_rng(3))
    st = r.state
    nb, blocked, dist = st.free.neighbour, st.free.blocked, st.free.distance
    rng = np.random.default_rng(0)
    tried = st.model.successor >= 0
    n_tied = n_tried = 0
    for s in np.flatnonzero(dist > 0):
        toward = [a for a in range(4) if nb[s, a] >= 0 and not blocked[s, a]
                  and dist[nb[s, a]] == dist[s] - 1]
        picked = {int(act(st, int(s), rng)) for _ in range(12)}
        assert picked <= set(toward), (s, picked, toward)
        n_tied += len(toward) > 1 and len(picked) > 1
        n_tried += any(tried[s, a] for a in picked)
    assert n_tied > 0 and n_tried > 0


def test_model_acting_learns_paper_50_and_is_off_by_default(paper50_model):
    """Off by default, and then not listed in a run's record (records from before it, and
    the behaviour digests hashed from them, are unchanged); on, it is listed, round-trips,
    changes training and finds the optimal route."""
    from learning import config_from_fields

    assert RNHQLPlus().model_acting == 0 and "model_acting" not in RNHQLPlus().record_fields()
    on = RNHQLPlus(model_acting=1)
    assert on.record_fields()["model_acting"] == 1
    assert config_from_fields("rnh-ql+", on.record_fields()) == on
    assert config_from_fields("rnh-ql+", RNHQLPlus().record_fields()) == RNHQLPlus()
    a = train_tabular(on, paper50_model, 100, np.random.default_rng(1))
    b = train_tabular(RNHQLPlus(), paper50_model, 100, np.random.default_rng(1))
    assert not np.array_equal(a.steps, b.steps)
    assert a.final_route_length == a.optimal_length


def test_model_acting_needs_look_ahead_on_a_potential():
    with pytest.raises(ValueError, match="model_acting"):
        RNHQLPlus(model_acting=1, lookahead=0)
    with pytest.raises(ValueError, match="model_acting"):
        RNHQLPlus(model_acting=1, shaping_scale=0.0)
    with pytest.raises(ValueError, match="model_acting"):
        RNHQLPlusAblation(model_acting=1)


def test_model_test_walks_the_optimistic_models_route_unless_a_known_route_is_as_short(
        paper50_model):
    """model_test: where s has no known route, or a longer one than the model's
    distance, the test's move goes one move nearer G in the optimistic model (a move seen
    to work first among equal ones); where the known route is as short, it is followed."""
    from learning.methods.rnh_ql_plus.rules import exploit

    r = train_tabular(RNHQLPlus(model_test=1), paper50_model, 15, np.random.default_rng(2))
    st = r.state
    exploit(st, int(paper50_model.start))  # brings the known routes up to date
    nb, blocked, dist = st.free.neighbour, st.free.blocked, st.free.distance
    known = st.known.distance
    works = st.model.works > st.model.fails
    n_model = n_known = 0
    for s in np.flatnonzero(dist > 0):
        a = int(exploit(st, int(s)))
        toward = [b for b in range(4) if nb[s, b] >= 0 and not blocked[s, b]
                  and dist[nb[s, b]] == dist[s] - 1]
        assert a in toward, (s, a, toward)
        if known[s] == dist[s]:
            assert works[s, a] and known[nb[s, a]] == known[s] - 1
            n_known += 1
        else:
            assert works[s, a] or not any(works[s, b] for b in toward)
            n_model += 1
    assert n_model > 0 and n_known > 0
    default = RNHQLPlus()
    assert "model_test" not in default.record_fields()
    assert RNHQLPlus(model_test=1).record_fields()["model_test"] == 1


def test_coverage_distances_are_a_bfs_back_from_every_unvisited_cell():
    """unvisited_distances on a 1 x 5 corridor, cells 0-2 visited, 3-4 not: distances
    3, 2, 1, 0, 0; with the move 1->2 blocked, 0 and 1 reach none (-1); G is no source."""
    from learning.parts.coverage import unvisited_distances

    nb = np.full((5, 4), -1, np.int32)  # up, down, left, right
    for s in range(5):
        nb[s, 2] = s - 1 if s > 0 else -1
        nb[s, 3] = s + 1 if s < 4 else -1
    succ = np.full((5, 4), -1, np.int32)
    succ[0:3, 3] = [1, 2, 3]
    blocked = np.zeros((5, 4), np.bool_)
    dist = np.zeros(5, np.int32)
    queue = np.zeros(5, np.int32)
    unvisited_distances(nb, blocked, succ, -1, dist, queue)
    assert dist.tolist() == [3, 2, 1, 0, 0]
    blocked[1, 3] = True
    unvisited_distances(nb, blocked, succ, -1, dist, queue)
    assert dist.tolist() == [-1, -1, 1, 0, 0]
    unvisited_distances(nb, blocked, succ, 4, dist, queue)  # G at 4
    assert dist.tolist() == [-1, -1, 1, 0, 1]  # G is no source, but a cell like any


def test_the_coverage_walk_tries_a_move_in_every_free_cell_and_then_ends(paper50_model):
    """explore_steps: with steps enough, the walk acts in every free cell it can
    reach (obstacle cells it bumps instead: none has a move tried) and marks itself done;
    the model then knows every wall, and model_test's route is optimal; with 0 it is the
    default, not listed."""
    m = paper50_model
    r = train_tabular(RNHQLPlus(explore_steps=20_000, model_test=1), m, 40,
                      np.random.default_rng(5))
    st = r.state
    acted = (st.model.successor >= 0).any(axis=1)
    free = np.asarray(m.distance_to_goal) > 0  # reachable free cells but G
    assert acted[free].all()
    assert not acted[np.asarray(m.distance_to_goal) < 0].any()
    assert st.coverage.done[0]
    assert r.final_route_length == r.optimal_length
    assert "explore_steps" not in RNHQLPlus().record_fields()
    a = train_tabular(RNHQLPlus(explore_steps=50), m, 30, np.random.default_rng(1))
    b = train_tabular(RNHQLPlus(), m, 30, np.random.default_rng(1))
    assert not np.array_equal(a.steps, b.steps)


@pytest.mark.parametrize("field, value", [("explore_steps", -2), ("model_test", 2),
                                          ("model_acting", 3), ("known_route", -1),
                                          ("untried_bonus", -1.0)])
def test_the_model_options_refuse_values_they_do_not_have(field, value):
    with pytest.raises(ValueError, match=rf"RNHQLPlus\.{field} = {value} must be"):
        RNHQLPlus(**{field: value})


def test_the_untried_bonus_sends_the_q_behaviour_to_moves_it_has_not_tried():
    """untried_bonus: Q starts at the bonus, and the epsilon-greedy Q behaviour (no walk,
    no model acting) then tries twice as many moves as without it, same seed; the greedy
    test never counts the bonus (a fresh agent's test moves are the default's); at 0 it is
    the default, not listed. (Counted: moves tried, cell and direction.)"""
    from learning import make_agent
    from scenarios.runs.spec import load

    m = load("paper-50", None, None, "goal-only")[1]  # the held-out studies' rewards
    geom = geometry_of(m)
    fresh = [make_agent(RNHQLPlus(untried_bonus=b), geom, np.random.default_rng(0))
             for b in (0.0, 100.0)]
    assert np.all(fresh[1].state.q == 100.0) and np.all(fresh[0].state.q == 0.0)
    for agent in fresh:
        agent.begin_episode(int(m.start))
    assert [fresh[0].greedy_action(s) for s in range(m.n_states)] == \
        [fresh[1].greedy_action(s) for s in range(m.n_states)]
    acted = []
    for b in (0.0, 100.0):  # the goal's reward: an untried move is worth reaching G
        st = train_tabular(RNHQLPlus(untried_bonus=b), m, 30, np.random.default_rng(3)).state
        acted.append(int((st.model.successor >= 0).sum()))
    assert acted[1] > 2 * acted[0], acted
    assert "untried_bonus" not in RNHQLPlus().record_fields()
    assert RNHQLPlus(untried_bonus=100).record_fields()["untried_bonus"] == 100


def test_rnh_ql_plus_explore_is_rnh_ql_plus_with_the_model_options(paper50_model):
    """The named variant is rnh-ql+ with explore_steps=-1, model_acting, model_test on
    and no planned updates, run for run; its record lists the options and round-trips."""
    from learning import RNHQLPlusExplore, config_from_fields

    named = RNHQLPlusExplore()
    spelled = RNHQLPlus(explore_steps=-1, model_acting=1, model_test=1, n_planning=0)
    assert METHODS["rnh-ql+explore"] is RNHQLPlusExplore
    assert config_from_fields("rnh-ql+explore", named.record_fields()) == named
    listed = named.record_fields()
    assert (listed["explore_steps"], listed["model_acting"], listed["model_test"],
            listed["n_planning"]) == (-1, 1, 1, 0)
    a = train_tabular(named, paper50_model, 40, np.random.default_rng(2))
    b = train_tabular(spelled, paper50_model, 40, np.random.default_rng(2))
    np.testing.assert_array_equal(a.steps, b.steps)
    np.testing.assert_array_equal(a.state.q, b.state.q)
    assert a.final_route_length == a.optimal_length


def test_rnh_ql_plus_explore_chooses_nothing_by_q(paper50_model):
    """Why it runs no planned updates (its docstring): with model_acting and model_test the
    behaviour and the greedy test read the optimistic model and the moves seen to work,
    never Q. Q scrambled, every greedy move and every behaviour move (same draws) stays."""
    from learning import RNHQLPlusExplore, copy_state, greedy_test, make_agent

    m = paper50_model
    trained = train_tabular(RNHQLPlusExplore(), m, 20, np.random.default_rng(4)).state
    agents = []
    for q in (trained.q.copy(), np.random.default_rng(9).normal(size=trained.q.shape) * 1e3):
        agent = make_agent(RNHQLPlusExplore(), geometry_of(m), np.random.default_rng(7))
        agent.state = copy_state(trained)._replace(q=q)  # each its own arrays
        agents.append(agent)
    routes = [greedy_test(agent.state, m)[1] for agent in agents]
    assert routes[0] == routes[1] and len(routes[0]) > 1
    for agent in agents:
        agent.begin_episode(int(m.start))  # the coverage walk is over or not: both alike
    for s in range(0, m.n_states, 7):
        assert agents[0].greedy_action(s) == agents[1].greedy_action(s)
        assert agents[0].act(s) == agents[1].act(s)


def test_the_walk_budget_grows_with_the_arena(paper50_model):
    """explore_steps=-1 (rnh-ql+explore's): 4 x the arena's longer side, so a run's walk is
    a fixed multiple of the arena's cells; an explicit budget is kept as given."""
    from learning import RNHQLPlusExplore, make_agent
    from learning.parts.coverage import walk_budget

    geom = geometry_of(paper50_model)
    side = round(max(geom.bounds_m[2] - geom.bounds_m[0], geom.bounds_m[3] - geom.bounds_m[1])
                 / geom.cell_size_m)
    assert side == 50
    agent = make_agent(RNHQLPlusExplore(), geom, np.random.default_rng(0))
    assert agent.state.par.explore_steps == walk_budget(-1, geom) == 4 * side
    assert walk_budget(1000, geom) == 1000

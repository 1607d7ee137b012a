"""The reference methods' rules: LRTA* (Korf 1990), the free-space replanner (the
free-space assumption of D* Lite) and R-max with a free-space Φ (Brafman & Tennenholtz
2002, Asmuth et al. 2008), on the exact grid where a bump is a wall."""

from __future__ import annotations

import numpy as np
import pytest

from learning import METHODS, train_tabular
from learning.methods.references.fsa_replan import FSAReplan
from learning.methods.references.lrta_star import LRTAStar
from learning.methods.references.r_max import RMax, q_table
from learning.parts.free_space import bfs_distances
from learning.parts.move_reading import count_outcome
from sim.grid import build_model
from sim.scenario_io import resolve_scenario


@pytest.fixture(scope="module")
def paper40():
    return build_model(resolve_scenario("paper-40"))


def _walls(model) -> np.ndarray:
    """bool[nS, nA]: the moves that bump (the grid model stays put)."""
    states = np.arange(model.next_state.shape[0])[:, None]
    return (model.next_state == states) & ~model.terminal[:, None]


def test_lrta_star_raises_an_admissible_heuristic_and_learns_the_optimal_route(paper40):
    res = train_tabular(LRTAStar(), paper40, 300, np.random.default_rng(0))
    st = res.state
    geom_cells = np.stack([np.arange(paper40.nx * paper40.ny) % paper40.nx,
                           np.arange(paper40.nx * paper40.ny) // paper40.nx], axis=1)
    gx, gy = geom_cells[paper40.goal]
    manhattan = np.abs(geom_cells[:, 0] - gx) + np.abs(geom_cells[:, 1] - gy)
    free = paper40.distance_to_goal >= 0
    assert (st.h >= manhattan - 1e-9).all()  # never lowered below its start
    assert (st.h[free] <= paper40.distance_to_goal[free] + 1e-9).all()  # still admissible
    assert st.h[paper40.goal] == 0.0
    assert not (st.blocked & ~_walls(paper40)).any()  # a belief of a wall is a wall
    assert res.final_route_length == res.optimal_length


def test_the_replanner_keeps_the_optimistic_maps_distances_and_its_route_is_optimal(paper40):
    res = train_tabular(FSAReplan(), paper40, 200, np.random.default_rng(1))
    fs = res.state.free
    assert not (fs.blocked & ~_walls(paper40)).any()
    # the repaired distances are the BFS over the moves believed free
    again = np.zeros_like(fs.distance)
    bfs_distances(fs.neighbour, fs.blocked, again, np.zeros_like(fs.queue), int(fs.goal[0]))
    assert (again == fs.distance).all()
    assert (fs.distance[paper40.distance_to_goal >= 0]
            <= paper40.distance_to_goal[paper40.distance_to_goal >= 0]).all()  # optimistic
    assert res.final_route_length == res.optimal_length


@pytest.mark.parametrize("cfg", [LRTAStar(), FSAReplan(), RMax(), RMax(m=2)],
                         ids=lambda c: f"{c.cli}-{getattr(c, 'm', '')}")
def test_a_seed_gives_the_same_run(paper40, cfg):
    a = train_tabular(cfg, paper40, 30, np.random.default_rng(5))
    b = train_tabular(cfg, paper40, 30, np.random.default_rng(5))
    assert (a.steps == b.steps).all() and a.final_route == b.final_route


def test_a_stray_bump_is_outvoted_by_the_moves_arrivals():
    """A noisy world's bump on a free move blocks it until clean arrivals outnumber it."""
    bal = np.zeros((2, 4), np.int32)
    nb = np.array([[1, -1, -1, -1], [-1, 0, -1, -1]], np.int32)
    assert count_outcome(bal, nb, 0, 0, 0, False) == 1  # bumped: blocked
    assert count_outcome(bal, nb, 0, 0, 1, True) == -1  # arrived cleanly: free again
    assert count_outcome(bal, nb, 0, 0, 1, True) == 0
    assert count_outcome(bal, nb, 0, 0, 0, False) == 0  # one bump against one arrival


def test_options_the_references_do_not_read_are_refused():
    for cls in (LRTAStar, FSAReplan, RMax):
        with pytest.raises(ValueError, match="do not read alpha"):
            cls(alpha=0.2)
        assert cls().eps == 0.0 and METHODS[cls.cli] is cls


def test_r_max_freezes_a_move_after_m_tries_and_its_costs_are_admissible(paper40):
    """Every move tried m times is known, with the bump share of its m tries; an untried
    move is valued 1 + Φ (the free-space distance, never above the true one), so every
    cell's cost is at most its true distance to G, and the final route is the optimum."""
    for m in (1, 2):
        res = train_tabular(RMax(m=m), paper40, 200, np.random.default_rng(3))
        st = res.state
        assert st.tries.max() <= m and (st.clean <= st.tries).all()
        known = st.tries == m
        walls = _walls(paper40)
        assert (st.clean[known & walls] == 0).all()  # a wall bumps every try (exact grid)
        assert (st.clean[known & ~walls] == m).all()
        assert st.version[0] == known.sum()  # one version per move that became known
        free = paper40.distance_to_goal > 0  # G's own cost is 0, not a move's
        cost = -q_table(st).max(axis=1)
        assert (cost[free] <= paper40.distance_to_goal[free] + 1e-9).all()
        assert (st.phi[free] <= paper40.distance_to_goal[free]).all()
        assert res.final_route_length == res.optimal_length


def test_r_max_values_an_untried_move_by_phi_and_a_known_one_by_its_bumps():
    """Two cells, G at 1: the move 0 -> 1 untried costs 1 + Φ(1) = 1; known after one
    bump in two tries (m = 2) it costs 2 expected tries; known to always bump, none."""
    from learning.geometry import Geometry
    from learning.methods.references.r_max import init_state, move_costs, refresh_costs

    geom = Geometry(np.array([[0.5, 0.5], [1.5, 0.5]]), 1, (0.0, 0.0, 2.0, 1.0), 2, 4)
    st = init_state(RMax(m=2), geom, np.random.default_rng(0))
    right = 3
    keys = np.zeros(4)
    refresh_costs(st)
    move_costs(st, 0, keys)
    assert keys[right] == 1.0 and (keys[:2] < 0).all()  # up and down leave the arena
    st.tries[0, right], st.clean[0, right] = 2, 1
    st.version[0] += 1
    refresh_costs(st)
    move_costs(st, 0, keys)
    assert keys[right] == 2.0
    st.clean[0, right] = 0
    st.version[0] += 1
    refresh_costs(st)
    move_costs(st, 0, keys)
    assert keys[right] < 0 and st.cost[0] == np.inf  # its only move always bumps


@pytest.mark.parametrize("m", [1, 3])
def test_r_max_repairs_its_costs_to_what_a_dijkstra_from_scratch_computes(paper40, m):
    """After every model change (a move becoming known free, bumping, or with a bump share
    of 1/3 or 2/3 at m = 3, hence costs like 1.5), the incrementally repaired costs and
    look-aheads equal a full Dijkstra's number for number, and the repair left nothing
    queued."""
    from learning.geometry import geometry_of
    from learning.methods.references.r_max import init_state, model_changed, refresh_costs, settle

    rng = np.random.default_rng(11)
    st = init_state(RMax(m=m), geometry_of(paper40), rng)
    refresh_costs(st)
    walls = _walls(paper40)
    n_a = st.tries.shape[1]
    rises = falls = 0
    for i, j in enumerate(rng.permutation(st.tries.size)):  # every move, in a random order
        s, a = divmod(int(j), n_a)
        if st.neighbour[s, a] < 0:
            continue
        before = st.cost.copy()
        st.tries[s, a] = m
        st.clean[s, a] = 0 if walls[s, a] else m - int(rng.random() < 0.2) * (m - 1)
        st.version[0] += 1
        model_changed(st, s)
        settle(st, -1)
        assert st.cost_version[0] == st.version[0] and st.field.open.size[0] == 0
        repaired = st.cost.copy()
        rises += int((repaired > before).sum())
        falls += int((repaired < before).sum())
        if i % 4 == 0:  # an error would persist: checking every fourth change finds it
            st.cost_version[0] = -1
            refresh_costs(st)
            np.testing.assert_array_equal(repaired, st.cost)
    assert rises > 300 and falls == 0  # learning a move only ever raises optimistic costs


def test_the_abstractions_value_follows_the_coarse_map_given_in_advance():
    """12 x 4 cells in three 4 x 4 blocks, G in the left one: with no map every block is
    linked to the next; with the middle block's cells all blocked, no abstract route
    reaches the right block, whose Φ is 0; Φ falls by gamma^block a block."""
    from learning.geometry import Geometry
    from learning.methods.references.abstraction_ql import AbstractionQL, abstract_distances

    xs, ys = np.meshgrid(np.arange(12), np.arange(4), indexing="xy")
    coords = np.stack([xs.ravel() + 0.5, ys.ravel() + 0.5], axis=1)
    geom = Geometry(coords, 0, (0.0, 0.0, 12.0, 4.0), 48, 4)
    z, d = abstract_distances(geom, 4)
    assert d.tolist() == [0, 1, 2] and z[0] == 0 and z[11] == 2
    cfg = AbstractionQL(block=4)
    phi = cfg.potential(geom)
    assert phi[0] == cfg.omega and phi[4] == pytest.approx(cfg.omega * cfg.gamma ** 4)
    walled = Geometry(coords, 0, (0.0, 0.0, 12.0, 4.0), 48, 4,
                      map_prior=~((coords[:, 0] > 4) & (coords[:, 0] < 8)))
    assert abstract_distances(walled, 4)[1].tolist() == [0, -1, -1]
    assert (cfg.potential(walled)[coords[:, 0] > 8] == 0.0).all()


def test_abstraction_ql_is_told_the_map_and_learns_on_paper40(paper40):
    """Its geometry carries the map (the one method that reads it); its greedy test is
    Q's (shaping by a potential leaves the optimal policy unchanged), and a seed repeats."""
    from learning.geometry import geometry_of
    from learning.methods.references.abstraction_ql import AbstractionQL

    geom = geometry_of(paper40)
    assert (geom.map_prior == (paper40.distance_to_goal >= 0)).all()
    a = train_tabular(AbstractionQL(), paper40, 40, np.random.default_rng(2))
    b = train_tabular(AbstractionQL(), paper40, 40, np.random.default_rng(2))
    assert (a.steps == b.steps).all() and (a.state.q == b.state.q).all()
    assert a.state.tally.n_shaped[0] > 0

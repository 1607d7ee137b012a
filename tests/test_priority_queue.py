"""The pair queue of prioritized sweeping, and rnh-ql+ with sweeping on."""

from __future__ import annotations

import numpy as np
import pytest

from learning.parts.priority_queue import new_pair_queue, pop, push


def test_pops_come_largest_first_and_a_pair_is_queued_once():
    rng = np.random.default_rng(3)
    q = new_pair_queue(50)
    best: dict[int, float] = {}
    for _ in range(400):
        j, p = int(rng.integers(0, 50)), float(rng.random())
        push(q.key, q.pair, q.where, q.size, j, p)
        best[j] = max(best.get(j, 0.0), p)
        if rng.random() < 0.3:  # interleaved pops take the largest queued priority
            top = pop(q.key, q.pair, q.where, q.size)
            assert best[top] == max(best.values())
            del best[top]
    assert q.size[0] == len(best)
    out = [pop(q.key, q.pair, q.where, q.size) for _ in range(len(best))]
    assert sorted(best, key=lambda j: -best[j]) == out
    assert pop(q.key, q.pair, q.where, q.size) == -1 and (q.where == -1).all()


def test_rnh_ql_plus_sweeping_learns_the_optimal_route(paper50_model):
    from learning import RNHQLPlus, train_tabular

    res = train_tabular(RNHQLPlus(sweeping=1), paper50_model, 200, np.random.default_rng(0),
                        test_every=10)
    assert res.final_route_length == paper50_model.optimal_route_length
    plain = train_tabular(RNHQLPlus(), paper50_model, 200, np.random.default_rng(0),
                          test_every=10)
    assert not np.array_equal(res.state.q, plain.state.q)  # the sweep did update other pairs
    assert res.state.sweep.where.shape[0] == res.state.q.size and plain.state.sweep.key.size == 0


def test_sweeping_needs_the_optimistic_potential():
    from learning import RNHQLPlusAblation

    with pytest.raises(ValueError, match="sweeping"):
        RNHQLPlusAblation(sweeping=1, v_target=1)

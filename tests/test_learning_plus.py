"""RNH-QL+: sparse features, leak-free supports, and the Dyna-Q limit (shaping_scale = 0)."""

from __future__ import annotations

import numpy as np

from learning import METHODS, geometry_of, train_tabular
from learning.methods import RNHQLPlus
from learning.plus_features import sparse_features


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
    a = train_tabular(RNHQLPlus(shaping_scale=0.0, n_planning=5), paper50_model, 30,
                      np.random.default_rng(3))
    b = train_tabular(METHODS["dyna-q"](), paper50_model, 30, np.random.default_rng(3))
    np.testing.assert_array_equal(a.state.q, b.state.q)
    np.testing.assert_array_equal(a.steps, b.steps)


def test_leak_free_supports_only_grow_along_seen_moves(paper50_model):
    r = train_tabular(RNHQLPlus(leak_free=1), paper50_model, 20, np.random.default_rng(0))
    feat = r.state.feat
    m = feat.shape[1] // 2
    on = feat[:, :m] > 0
    assert on.any() and np.all(feat[:, :m][on] == feat[:, m:][on])
    visited = (r.state.imap[:, :4] >= 0).any(axis=1)
    # a cell with a switched-on feature has been visited or is the end of a seen move
    ends = np.zeros_like(visited)
    seen = r.state.imap[:, :4][r.state.imap[:, :4] >= 0]
    ends[seen] = True
    assert np.all((visited | ends)[on.any(axis=1)])


def test_readout_potential_equals_the_networks_value():
    """The recorder's V_NN heat map for rnh-ql+ is the value the rules compute."""
    import numpy as np

    from learning.methods import METHODS
    from learning.readout import potential
    from learning.rules_plus import v_of
    from learning.train import train_tabular
    from scenarios.runs.spec import load

    _, m = load("paper-40", None, None, "goal-only")
    st = train_tabular(METHODS["rnh-ql+"](), m, 100, np.random.default_rng(0)).state
    ref = np.array([v_of(st.w, st.feat, st.imap, s) for s in range(m.n_states)])
    np.testing.assert_allclose(potential(st), ref, atol=1e-12)
    assert np.abs(ref).max() > 0

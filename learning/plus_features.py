"""RNH-QL+'s features: a map-sized lattice, sparse Gaussian features, leak-free supports.

Split from :mod:`learning.rules_plus` (the update rules and agent events). Built
once per agent in numpy (:func:`init_plus`); the leak-free flood fill runs in
numba when the agent sees a new move succeed. Layout of the slots: see
:mod:`learning.rules_plus`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from learning.explored import COL_NEXT, init_explored
from learning.geometry import Geometry
from learning.plus_optimism import optimistic_bfs

# ---------------------------------------------------------------- features (numpy, once)


def lattice(geom: Geometry, spacing: int, k: int, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """(centres float64[K, 2], width float64[2]) in cell units (cell ix spans [ix, ix+1)).

    ``spacing`` > 0: a centre every ``spacing`` cells, the lattice centred on
    the map; 0: the paper's k x k lattice over the arena. Width = sigma * pitch.
    """
    cs = geom.cell_size_m
    nx = round((geom.bounds_m[2] - geom.bounds_m[0]) / cs)
    ny = round((geom.bounds_m[3] - geom.bounds_m[1]) / cs)
    if spacing > 0:
        def axis(n: int) -> np.ndarray:
            m = max(1, -(-n // spacing))
            off = (n - (m - 1) * spacing) / 2.0
            return off + spacing * np.arange(m)
        cx, cy, h = axis(nx), axis(ny), np.array([spacing, spacing], dtype=float)
    else:
        hx, hy = nx / k, ny / k
        cx, cy, h = (np.arange(k) + 0.5) * hx, (np.arange(k) + 0.5) * hy, np.array([hx, hy])
    gx, gy = np.meshgrid(cx, cy)
    return np.column_stack([gx.ravel(), gy.ravel()]), sigma * h


def sparse_features(geom: Geometry, spacing: int, k: int, sigma: float, cutoff: float,
                    normalise: bool) -> tuple[np.ndarray, np.ndarray, int]:
    """(values float64[nS, M], centre ids int32[nS, M], K): each state's Gaussian features
    exp(-d^2/2) (d in widths) of the centres with d <= cutoff (all if cutoff = 0), nearest
    first; unused slots have value 0 and id 0. ``normalise``: each row sums to 1."""
    centres, width = lattice(geom, spacing, k, sigma)
    pos = geom.cells.astype(np.float64) + 0.5
    n_s, n_c = pos.shape[0], centres.shape[0]
    ids = np.arange(n_c)
    if cutoff > 0:  # candidate centres: a window of lattice indices around each state
        ncx = len(np.unique(centres[:, 0]))
        pitch = width / sigma
        c0 = centres[0]
        jx0 = np.floor((pos[:, 0] - c0[0]) / pitch[0]).astype(int)
        jy0 = np.floor((pos[:, 1] - c0[1]) / pitch[1]).astype(int)
        r = math.ceil(cutoff * sigma) + 1
        ncy = n_c // ncx
        cand = []
        for oy in range(-r, r + 2):
            for ox in range(-r, r + 2):
                jx, jy = jx0 + ox, jy0 + oy
                ok = (jx >= 0) & (jx < ncx) & (jy >= 0) & (jy < ncy)
                cand.append(np.where(ok, jy * ncx + jx, -1))
        cid = np.stack(cand, axis=1)
    else:
        cid = np.broadcast_to(ids, (n_s, n_c)).copy()
    safe = np.maximum(cid, 0)
    d = (pos[:, None, :] - centres[safe]) / width
    d2 = np.sum(d * d, axis=2)
    val = np.exp(-0.5 * d2)
    keep = cid >= 0
    if cutoff > 0:
        keep &= d2 <= cutoff * cutoff
    d2 = np.where(keep, d2, np.inf)
    order = np.argsort(d2, axis=1, kind="stable")
    m = max(1, int(keep.sum(axis=1).max()))
    order = order[:, :m]
    rows = np.arange(n_s)[:, None]
    vals = np.where(keep[rows, order], val[rows, order], 0.0)
    cids = np.where(keep[rows, order], safe[rows, order], 0).astype(np.int32)
    if normalise:
        tot = vals.sum(axis=1, keepdims=True)
        vals = np.where(tot > 0, vals / np.where(tot > 0, tot, 1.0), 0.0)
    return np.ascontiguousarray(vals), np.ascontiguousarray(cids), n_c


def init_plus(cfg, geom: Geometry) -> dict[str, np.ndarray]:
    """The RNH-QL+ slots (see the module docs) and the V_NN step size fvar[F_STEP_V]."""
    n_s, n_a = geom.n_states, geom.n_actions
    base, cids, n_c = sparse_features(geom, cfg.spacing, cfg.k, cfg.sigma, cfg.cutoff,
                                      bool(cfg.normalise))
    m = base.shape[1]
    feat = np.zeros((n_s, 2 * m))
    feat[:, m:] = base
    if not cfg.leak_free:
        feat[:, :m] = base
    imap = np.full((n_s, 3 * n_a + m), -1, dtype=np.int32)
    imap[:, n_a:2 * n_a] = 0
    imap[:, 2 * n_a:2 * n_a + m] = cids
    ilist = np.zeros(2 * n_s * n_a + n_c + 3 * n_s * n_a + 3 * n_s, dtype=np.int32)
    a0 = 2 * n_s * n_a
    ilist[a0:a0 + n_c] = -1
    # the arena's neighbour table (the agent knows the cells, not the obstacles)
    ilist[a0 + n_c:a0 + n_c + n_s * n_a] = init_explored(geom, False)[0][:, COL_NEXT:].ravel()
    optimistic_bfs(imap, ilist, n_s, n_a, n_c, int(geom.goal))
    step_v = cfg.beta / float(np.mean(np.sum(base * base, axis=1)))
    e = np.zeros(n_c + 2 * n_s + 2)
    e[n_c + 2 * n_s] = -1.0  # y not computed yet (learning.plus_optimism)
    return dict(q=np.zeros((n_s, n_a)), w=np.zeros(n_c), e=e, feat=feat,
                imap=imap, fmap=np.zeros((2 * n_s + 1, n_a)), ilist=ilist, step_v=step_v,
                goal=int(geom.goal))


# ---------------------------------------------------------------- V_NN over sparse features


@njit(cache=True)
def _slot(feat, imap, off, c, i):
    """Feature slot of centre i at state c, -1 if c is outside i's support window."""
    m_n = feat.shape[1] // 2
    for m in range(m_n):
        if imap[c, off + m] == i and feat[c, m_n + m] > 0.0:
            return m
    return -1


@njit(cache=True)
def _switch_on(feat, c, m, normalise):
    m_n = feat.shape[1] // 2
    feat[c, m] = feat[c, m_n + m]
    if normalise:  # renormalise the row over the switched-on features (bases sum to 1)
        tot = 0.0
        for j in range(m_n):
            if feat[c, j] > 0.0:
                tot += feat[c, m_n + j]
        for j in range(m_n):
            if feat[c, j] > 0.0:
                feat[c, j] = feat[c, m_n + j] / tot


@njit(cache=True)
def _flood(feat, imap, ilist, stack0, off, roff, n_a, i, c, normalise):
    """Switch centre i on at c and at every cell of i's window connected to c by seen moves."""
    m = _slot(feat, imap, off, c, i)
    if m < 0 or feat[c, m] > 0.0:
        return
    _switch_on(feat, c, m, normalise)
    ilist[stack0] = c
    top = 1
    while top > 0:
        top -= 1
        x = ilist[stack0 + top]
        for j in range(2 * n_a):
            y = imap[x, j] if j < n_a else imap[x, roff + j - n_a]
            if y < 0 or y == x:
                continue
            my = _slot(feat, imap, off, y, i)
            if my >= 0 and feat[y, my] == 0.0:
                _switch_on(feat, y, my, normalise)
                ilist[stack0 + top] = y
                top += 1


@njit(cache=True)
def leak_free_enter(feat, imap, ilist, n_s, n_a, s, normalise):
    """On entering s: if s's nearest centre has no anchor yet, s becomes it and the
    centre's support is flooded from s."""
    m_n = feat.shape[1] // 2
    off = 2 * n_a
    a0 = 2 * n_s * n_a
    i = imap[s, off]
    if ilist[a0 + i] < 0 and feat[s, m_n] > 0.0:
        ilist[a0 + i] = s
        _flood(feat, imap, ilist, ilist.shape[0] - n_s, off, off + m_n, n_a, i, s, normalise)


@njit(cache=True)
def leak_free_edge(feat, imap, ilist, n_s, n_a, s, s2, normalise):
    """A move s -> s2 was seen for the first time: remember s as a predecessor of s2, and
    join s2 (or s) to every support that holds s (or s2) and whose window holds both."""
    m_n = feat.shape[1] // 2
    off = 2 * n_a
    roff = off + m_n
    for k in range(n_a):
        if imap[s2, roff + k] == s:
            break
        if imap[s2, roff + k] < 0:
            imap[s2, roff + k] = s
            break
    stack0 = ilist.shape[0] - n_s
    for m in range(m_n):
        if feat[s, m_n + m] <= 0.0:
            continue
        i = imap[s, off + m]
        m2 = _slot(feat, imap, off, s2, i)
        if m2 < 0:
            continue
        on1 = feat[s, m] > 0.0
        on2 = feat[s2, m2] > 0.0
        if on1 and not on2:
            _flood(feat, imap, ilist, stack0, off, roff, n_a, i, s2, normalise)
        elif on2 and not on1:
            _flood(feat, imap, ilist, stack0, off, roff, n_a, i, s, normalise)

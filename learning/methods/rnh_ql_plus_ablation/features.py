"""The RNH-QL+ ablation's features: a map-sized lattice, sparse Gaussian features,
leak-free supports.

Built once per agent in numpy (:func:`new_features`); the leak-free flood fill
runs in numba when the agent sees a new move succeed.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from learning.geometry import Geometry


class Features(NamedTuple):
    """M feature slots per state, each one of the K centres (nearest first)."""

    on: np.ndarray  # float64[nS, M]; the values in effect (leak-free: 0 until switched on)
    base: np.ndarray  # float64[nS, M]; the Gaussian values (derived)
    centre: np.ndarray  # int32[nS, M]; the centre of each slot (derived)
    preds: np.ndarray  # int32[nS, nA]; states seen to move into this one (-1: none)
    anchor: np.ndarray  # int32[K]; the first visited cell nearest each centre (-1: none)
    stack: np.ndarray  # int32[nS]; the flood fill's stack


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


def no_features(n_actions: int) -> Features:
    """Empty features, for a configuration that never reads them (no network, no leak-free
    supports): building them took most of a 512² run's memory (1.3 GB peak, a 94 MB
    checkpoint) for nothing."""
    return Features(np.zeros((0, 0)), np.zeros((0, 0)), np.zeros((0, 0), np.int32),
                    np.full((0, n_actions), -1, np.int32), np.zeros(0, np.int32),
                    np.zeros(0, np.int32))


def new_features(cfg, geom: Geometry) -> Features:
    if not cfg.uses_features:
        return no_features(geom.n_actions)
    base, cids, n_c = sparse_features(geom, cfg.spacing, cfg.k, cfg.sigma, cfg.cutoff,
                                      bool(cfg.normalise))
    n_s, n_a = geom.n_states, geom.n_actions
    on = np.zeros_like(base) if cfg.leak_free else base.copy()
    return Features(on, base, cids, np.full((n_s, n_a), -1, np.int32),
                    np.full(n_c, -1, np.int32), np.zeros(n_s, np.int32))


# ---------------------------------------------------------------- leak-free supports


@njit(cache=True)
def _slot(ft, c, i):
    """Feature slot of centre i at state c, -1 if c is outside i's support window."""
    for m in range(ft.on.shape[1]):
        if ft.centre[c, m] == i and ft.base[c, m] > 0.0:
            return m
    return -1


@njit(cache=True)
def _switch_on(ft, c, m, normalise):
    on = ft.on
    base = ft.base
    on[c, m] = base[c, m]
    if normalise:  # renormalise the row over the switched-on features (bases sum to 1)
        tot = 0.0
        for j in range(on.shape[1]):
            if on[c, j] > 0.0:
                tot += base[c, j]
        for j in range(on.shape[1]):
            if on[c, j] > 0.0:
                on[c, j] = base[c, j] / tot


@njit(cache=True)
def _flood(ft, successor, i, c, normalise):
    """Switch centre i on at c and at every cell of i's window connected to c by seen moves."""
    m = _slot(ft, c, i)
    if m < 0 or ft.on[c, m] > 0.0:
        return
    _switch_on(ft, c, m, normalise)
    stack = ft.stack
    n_a = successor.shape[1]
    stack[0] = c
    top = 1
    while top > 0:
        top -= 1
        x = stack[top]
        for j in range(2 * n_a):
            y = successor[x, j] if j < n_a else ft.preds[x, j - n_a]
            if y < 0 or y == x:
                continue
            my = _slot(ft, y, i)
            if my >= 0 and ft.on[y, my] == 0.0:
                _switch_on(ft, y, my, normalise)
                stack[top] = y
                top += 1


@njit(cache=True)
def leak_free_enter(on, base, centre, preds, anchor, stack, successor, s, normalise):
    """On entering s: if s's nearest centre has no anchor yet, s becomes it and the
    centre's support is flooded from s. Takes :class:`Features`' arrays, in its order
    (compiled hooks read a named tuple's fields once, at their top; see
    :mod:`learning.methods.rnh_ql_plus.rules`)."""
    ft = Features(on, base, centre, preds, anchor, stack)
    i = ft.centre[s, 0]
    if ft.anchor[i] < 0 and ft.base[s, 0] > 0.0:
        ft.anchor[i] = s
        _flood(ft, successor, i, s, normalise)


@njit(cache=True)
def leak_free_edge(on, base, centre, preds, anchor, stack, successor, s, s2, normalise):
    """A move s -> s2 was seen for the first time: remember s as a predecessor of s2, and
    join s2 (or s) to every support that holds s (or s2) and whose window holds both.
    Takes :class:`Features`' arrays, like :func:`leak_free_enter`."""
    ft = Features(on, base, centre, preds, anchor, stack)
    for k in range(preds.shape[1]):
        if preds[s2, k] == s:
            break
        if preds[s2, k] < 0:
            preds[s2, k] = s
            break
    for m in range(ft.on.shape[1]):
        if ft.base[s, m] <= 0.0:
            continue
        i = ft.centre[s, m]
        m2 = _slot(ft, s2, i)
        if m2 < 0:
            continue
        on1 = ft.on[s, m] > 0.0
        on2 = ft.on[s2, m2] > 0.0
        if on1 and not on2:
            _flood(ft, successor, i, s2, normalise)
        elif on2 and not on1:
            _flood(ft, successor, i, s, normalise)

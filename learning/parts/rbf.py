"""Gaussian RBF value network V_NN(s) = w . phi(s) and its TD(lambda) rule (RNH-QL's upper layer).

Centres sit on a cell-centred k x k lattice over the arena bounds; each
Gaussian's width is the lattice spacing along its axis. The input is the cell
centre in metres, so the same features serve the grid and the physics world.
The feature matrix ``phi[nS, K]`` is computed once (all the ``exp`` calls are
here); the hot loop only does dot products and axpys over K, inlined into the
kernel (``inline="always"``: 4.6M -> 5.3M RNH-QL steps/s on paper-50).
"""

from __future__ import annotations

import numpy as np
from numba import njit


def lattice_size(bounds_m: tuple[float, float, float, float], k: int,
                 spacing_m: float = 0.0) -> tuple[int, int]:
    """Centres per axis: ``k`` x ``k`` (the paper's), or one every ``spacing_m`` metres when
    ``spacing_m > 0``, so a large map is not covered by a 50 x 50 map's lattice."""
    if spacing_m > 0:
        xmin, ymin, xmax, ymax = bounds_m
        return (max(1, round((xmax - xmin) / spacing_m)),
                max(1, round((ymax - ymin) / spacing_m)))
    return k, k


def rbf_centres(bounds_m: tuple[float, float, float, float], k: int,
                ky: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(centres float64[k*ky, 2] [m], sigma float64[2] [m]) of the cell-centred k x ky lattice
    (``ky`` defaults to ``k``)."""
    ky = k if ky is None else ky
    if k < 1 or ky < 1:
        raise ValueError(f"RBF lattice size must be >= 1 per axis, got {k} x {ky}")
    xmin, ymin, xmax, ymax = bounds_m
    hx, hy = (xmax - xmin) / k, (ymax - ymin) / ky
    cx = xmin + (np.arange(k) + 0.5) * hx
    cy = ymin + (np.arange(ky) + 0.5) * hy
    gx, gy = np.meshgrid(cx, cy)  # row-major: centre index = iy * k + ix
    return np.column_stack([gx.ravel(), gy.ravel()]), np.array([hx, hy])


def rbf_features(coords: np.ndarray, bounds_m: tuple[float, float, float, float],
                 k: int, ky: int | None = None) -> np.ndarray:
    """phi float64[nS, k*ky]: exp(-((x-cx)^2/sx^2 + (y-cy)^2/sy^2) / 2) at each cell centre.

    Dense: nS x K floats. For large maps with a fine lattice use ``rnh-ql+`` (sparse).
    """
    centres, sigma = rbf_centres(bounds_m, k, ky)
    d = (coords[:, None, :] - centres[None, :, :]) / sigma
    return np.ascontiguousarray(np.exp(-0.5 * np.sum(d * d, axis=2)))


@njit(cache=True, inline="always")
def value(phi, s, w):
    """V(s) = w . phi[s]."""
    v = 0.0
    for i in range(w.shape[0]):
        v += phi[s, i] * w[i]
    return v


@njit(cache=True, inline="always")
def td_lambda(w, e, phi, s, r, v_s2, greedy, gamma, lam, step):
    """One TD(lambda) step with Watkins trace cutting.

    delta = r + gamma * V(s') - V(s) (``v_s2`` is V(s'), already 0 on termination);
    greedy action: e <- gamma*lambda*e + phi(s), w <- w + step*delta*e;
    non-greedy: e <- 0 and w is unchanged this step.
    """
    k = w.shape[0]
    if not greedy:
        for i in range(k):
            e[i] = 0.0
        return
    delta = r + gamma * v_s2 - value(phi, s, w)
    gl = gamma * lam
    c = step * delta
    for i in range(k):
        ei = gl * e[i] + phi[s, i]
        e[i] = ei
        w[i] += c * ei

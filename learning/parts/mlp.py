"""RN-QL's function approximator: one 2-H-1 net per action (sigmoid hidden, linear output).

All nets live in one flat weight vector ``w`` (what the checkpoint stores), one
block of ``4H + 1`` weights per action: ``W1[H, 2]`` (row-major), ``b1[H]``,
``W2[H]``, ``b2``. Inputs are the cell centre normalised to [0, 1]^2 by the
arena bounds (precomputed per state). Outputs are Q / q_scale.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


def block_size(n_hidden: int) -> int:
    return 4 * n_hidden + 1


def init_weights(n_actions: int, n_hidden: int, init_range: float,
                 rng: np.random.Generator) -> np.ndarray:
    """U(-r, r) weights, drawn as one ``rng.uniform`` call of n_actions * (4H + 1) values."""
    return rng.uniform(-init_range, init_range, size=n_actions * block_size(n_hidden))


def normalised_inputs(coords: np.ndarray,
                      bounds_m: tuple[float, float, float, float]) -> np.ndarray:
    """float64[nS, 2]: cell centres mapped to [0, 1]^2 by the arena bounds."""
    xmin, ymin, xmax, ymax = bounds_m
    return np.ascontiguousarray((coords - np.array([xmin, ymin]))
                                / np.array([xmax - xmin, ymax - ymin]))


@njit(cache=True)
def _sigmoid(z):
    return 1.0 / (1.0 + math.exp(-z))


@njit(cache=True)
def n_hidden_of(w, n_actions):
    return (w.shape[0] // n_actions - 1) // 4


@njit(cache=True)
def net(w, x, s, a, n_hidden):
    """Output of action a's net at state s's input ``x[s]``."""
    o = a * (4 * n_hidden + 1)
    h2 = 2 * n_hidden
    out = w[o + 4 * n_hidden]
    for j in range(n_hidden):
        hj = _sigmoid(w[o + 2 * j] * x[s, 0] + w[o + 2 * j + 1] * x[s, 1] + w[o + h2 + j])
        out += w[o + 3 * n_hidden + j] * hj
    return out


@njit(cache=True)
def net_row(w, x, s, out, hid):
    """out[0, a] = net_a(x[s]) for every action (``out`` is float64[1, nA]); ``hid[a, j]``
    keeps each net's hidden activations there, which the gradient at s reuses."""
    n_actions = out.shape[1]
    n_hidden = n_hidden_of(w, n_actions)
    h2 = 2 * n_hidden
    x0, x1 = x[s, 0], x[s, 1]
    for a in range(n_actions):
        o = a * (4 * n_hidden + 1)
        v = w[o + 4 * n_hidden]
        for j in range(n_hidden):
            hj = _sigmoid(w[o + 2 * j] * x0 + w[o + 2 * j + 1] * x1 + w[o + h2 + j])
            hid[a, j] = hj
            v += w[o + 3 * n_hidden + j] * hj
        out[0, a] = v


@njit(cache=True)
def add_gradient(w, x, s, a, n_hidden, e):
    """e[block a] += d net_a(x[s]) / d w (back-propagation through the sigmoid layer), from
    scratch: the training step reuses the activations :func:`net_row` kept instead."""
    o = a * (4 * n_hidden + 1)
    h2 = 2 * n_hidden
    x0, x1 = x[s, 0], x[s, 1]
    hid = np.empty((a + 1, n_hidden))
    for j in range(n_hidden):
        hid[a, j] = _sigmoid(w[o + 2 * j] * x0 + w[o + 2 * j + 1] * x1 + w[o + h2 + j])
    _add_gradient_at(w, x0, x1, a, n_hidden, hid, e)


@njit(cache=True)
def _add_gradient_at(w, x0, x1, a, n_hidden, hid, e):
    """:func:`add_gradient` from the hidden activations ``hid[a]`` that :func:`net_row`
    kept at the same input (the same numbers, without their 10 exponentials)."""
    o = a * (4 * n_hidden + 1)
    h2 = 2 * n_hidden
    h3 = 3 * n_hidden
    for j in range(n_hidden):
        hj = hid[a, j]
        e[o + h3 + j] += hj  # dW2_j
        g = w[o + h3 + j] * hj * (1.0 - hj)
        e[o + 2 * j] += g * x0  # dW1_j0
        e[o + 2 * j + 1] += g * x1  # dW1_j1
        e[o + h2 + j] += g  # db1_j
    e[o + 4 * n_hidden] += 1.0  # db2


@njit(cache=True)
def q_lambda_net(w, e, x, s, a, r, s2, terminated, alpha, gamma, lam, q_scale, scratch, hid,
                 row_of):
    """Watkins Q(lambda) with gradient traces over the nets, in net units (Q / q_scale).

    delta = r/q_scale + gamma * max_b net_b(x_s') [not terminated] - net_a(x_s);
    traces: e <- gamma*lambda*e if a was greedy else 0; then e += grad net_a(x_s);
    w <- w + alpha * delta * e. ``scratch`` (float64[1, nA]) and ``hid`` (float64[nA, H])
    hold the nets' outputs and hidden activations at state ``row_of[0]`` for the current
    weights: the behaviour policy has just evaluated them at s, so they are reused, not
    recomputed (every number is the one the recomputation gives). The weights change
    here, so ``row_of[0]`` is -1 on return.
    """
    n_actions = scratch.shape[1]
    n_hidden = n_hidden_of(w, n_actions)
    if row_of[0] != s:
        net_row(w, x, s, scratch, hid)
    qa = scratch[0, a]
    greedy = True
    for b in range(n_actions):
        if scratch[0, b] > qa:
            greedy = False
    gl = gamma * lam if greedy else 0.0
    for i in range(e.shape[0]):
        e[i] *= gl
    _add_gradient_at(w, x[s, 0], x[s, 1], a, n_hidden, hid, e)  # before hid moves to s'
    target = r / q_scale
    if not terminated:
        net_row(w, x, s2, scratch, hid)
        m = scratch[0, 0]
        for b in range(1, n_actions):
            m = max(m, scratch[0, b])
        target += gamma * m
    delta = target - qa
    c = alpha * delta
    for i in range(w.shape[0]):
        w[i] += c * e[i]
    row_of[0] = -1

"""What every learner counts: episodes done and the shaping terms of the running episode.

A learner's state is a named tuple of arrays (numba cannot mutate a tuple's
scalars), so each count is a one-element array: ``st.tally.episode[0]``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class Tally(NamedTuple):
    episode: np.ndarray  # int64[1]; episodes completed = 0-based index of the running one
    n_shaped: np.ndarray  # int64[1]; shaping terms added this episode
    f_sum: np.ndarray  # float64[1]; their sum
    f_sq: np.ndarray  # float64[1]; their sum of squares
    f_mean: np.ndarray  # float64[1]; mean of the last finished episode's shaping terms
    f_std: np.ndarray  # float64[1]; their standard deviation


def new_tally() -> Tally:
    i, f = (lambda: np.zeros(1, dtype=np.int64)), (lambda: np.zeros(1, dtype=np.float64))
    return Tally(i(), i(), f(), f(), f(), f())


@njit(cache=True, inline="always")
def record_shaping(f_sum, f_sq, n_shaped, f, on):
    """Add the shaping term f to the episode's sums (:class:`Tally`'s ``f_sum``, ``f_sq``,
    ``n_shaped``) if ``on``. Called on every step with the switch inside, and with the three
    arrays, not the tally: a hook reads only the arrays it needs, once, at its top (see
    :mod:`learning.methods.rnh_ql_plus.rules`)."""
    if on:
        f_sum[0] += f
        f_sq[0] += f * f
        n_shaped[0] += 1


@njit(cache=True, inline="always")
def begin_tally(tally):
    """The running episode's shaping sums start at zero."""
    tally.n_shaped[0] = 0
    tally.f_sum[0] = 0.0
    tally.f_sq[0] = 0.0


@njit(cache=True, inline="always")
def end_tally(tally):
    """Close the episode: shaping mean and std, one more episode done."""
    n = tally.n_shaped[0]
    if n > 0:
        mean = tally.f_sum[0] / n
        tally.f_mean[0] = mean
        tally.f_std[0] = math.sqrt(max(tally.f_sq[0] / n - mean * mean, 0.0))
    else:
        tally.f_mean[0] = 0.0
        tally.f_std[0] = 0.0
    tally.episode[0] += 1

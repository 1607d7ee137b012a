"""Interval estimates over seeds: percentile bootstrap CIs and the probability of improvement.

numpy only. Every estimate takes a numpy ``Generator``, so the same values and the same
generator seed give the same interval; :func:`generator` is the seeded one rnhql's
reports use (:data:`SEED`), fresh per estimate so an interval does not depend on what
else was estimated before it.

**Never reached.** A ``None`` (never reached, G not reached) is the worst outcome a seed
can have. :func:`bootstrap_ci` counts it as ``+inf``, like :func:`quantile`: the median
of a resample is ``+inf`` as soon as its middle order statistic (or one of the two) is
``None``, and an interval end is ``+inf`` when the percentile lands on or interpolates
towards such a resample (so ``[40, inf]`` reads "at most 40 is ruled out, and it may
well never get there"). :func:`probability_of_improvement` counts it as the worst value
on the figure's side (``+inf`` when lower is better, ``-inf`` when higher is better): it
loses to every value and ties (½) with another ``None``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np

SEED = 34  # the reports' bootstrap seed (fixed: the same runs give the same interval)
N_RESAMPLES = 5000
LEVEL = 0.95

Stat = Callable[[np.ndarray], np.ndarray]


def median(samples: np.ndarray) -> np.ndarray:
    """Median along the last axis (type 7, as :func:`quantile`)."""
    return np.median(samples, axis=-1)


def generator(seed: int = SEED) -> np.random.Generator:
    """The seeded generator rnhql's reports resample with."""
    return np.random.default_rng(seed)


class Estimate(NamedTuple):
    """A point estimate with its percentile-bootstrap interval ``[lo, hi]``."""

    value: float
    lo: float
    hi: float

    def contains(self, v: float) -> bool:
        return self.lo <= v <= self.hi


def as_values(values: Sequence[float | None], never: float = math.inf) -> np.ndarray:
    """A 1-D float array, ``None`` replaced by ``never``."""
    return np.array([never if v is None else float(v) for v in values], dtype=float)


def _quantile_sorted(s: np.ndarray, q: float) -> float:
    """Type-7 quantile of sorted ``s``; interpolating towards an infinity gives it."""
    h = (s.size - 1) * q
    lo = math.floor(h)
    frac = h - lo
    if frac == 0.0 or lo + 1 >= s.size:
        return float(s[lo])
    a, b = float(s[lo]), float(s[lo + 1])
    if a == b:
        return a
    if b == math.inf:
        return math.inf
    if a == -math.inf:
        return -math.inf
    return a + (b - a) * frac


def percentile_interval(stats: np.ndarray, level: float = LEVEL) -> tuple[float, float]:
    """The central ``level`` interval of bootstrap statistics (type-7 percentiles)."""
    s = np.sort(np.asarray(stats, dtype=float).ravel())
    if s.size == 0:
        raise ValueError("percentile interval of no statistics")
    if np.isnan(s).any():
        raise ValueError("the bootstrap statistic gave NaN (inf - inf?)")
    alpha = (1.0 - level) / 2.0
    return _quantile_sorted(s, alpha), _quantile_sorted(s, 1.0 - alpha)


def bootstrap_ci(values: Sequence[float | None], stat: Stat = median,
                 rng: np.random.Generator | None = None, n_resamples: int = N_RESAMPLES,
                 level: float = LEVEL) -> tuple[float, float]:
    """Percentile bootstrap interval of ``stat`` over seeds.

    Resamples the seeds with replacement ``n_resamples`` times in one array
    (``n_resamples`` x seeds); ``stat`` reduces the last axis of that array (default
    :func:`median`). ``None`` counts as ``+inf`` (module docstring). One seed gives a
    zero-width interval at its value.
    """
    x = as_values(values)
    if x.size == 0:
        raise ValueError("bootstrap of no values")
    rng = generator() if rng is None else rng
    idx = rng.integers(0, x.size, size=(n_resamples, x.size))
    return percentile_interval(np.asarray(stat(x[idx]), dtype=float), level)


def _wins(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Pairwise score matrix: 1 where x_i > y_j, 1/2 where equal, 0 where less."""
    xi, yj = x[:, None], y[None, :]
    return (xi > yj) + 0.5 * (xi == yj)


def probability_of_improvement(x: Sequence[float | None], y: Sequence[float | None],
                               rng: np.random.Generator | None = None,
                               n_resamples: int = N_RESAMPLES, level: float = LEVEL,
                               lower_is_better: bool = False) -> Estimate:
    """P(X better than Y) over all seed pairs, ties ½, with a percentile-bootstrap interval.

    As rliable reports it (Agarwal et al. 2021, for one task): the point value is
    (1 / (n m)) sum_ij S(x_i, y_j), S = 1 if x_i is better, ½ on a tie, 0 otherwise.
    The interval resamples the seeds of X and of Y independently with replacement
    (stratified: each method keeps its seed count); a resample's value is the same sum
    weighted by how often each seed was drawn, so all resamples are one matrix product.
    ``None`` is the worst value (module docstring). 0.5 inside the interval means no
    evidence of a difference.
    """
    worst = math.inf if lower_is_better else -math.inf
    xa, ya = as_values(x, worst), as_values(y, worst)
    if xa.size == 0 or ya.size == 0:
        raise ValueError("probability of improvement needs seeds on both sides")
    if lower_is_better:
        xa, ya = -xa, -ya
    rng = generator() if rng is None else rng
    wins = _wins(xa, ya)
    n, m = wins.shape
    cx = rng.multinomial(n, np.full(n, 1.0 / n), size=n_resamples)
    cy = rng.multinomial(m, np.full(m, 1.0 / m), size=n_resamples)
    boot = np.einsum("bi,ij,bj->b", cx, wins, cy) / (n * m)
    lo, hi = percentile_interval(boot, level)
    return Estimate(float(wins.mean()), lo, hi)


# ------------------------------------------------------- across tasks (Agarwal et al. 2021)
def iqm(samples: np.ndarray) -> np.ndarray:
    """Interquartile mean along the last axis: the mean of the middle half of the values
    (the 25 % trimmed mean; a run's share of the sorted values that falls across a quarter
    counts in part, so any number of runs is exact). Robust to the seeds that never got
    there at either end, and less noisy than the median. It equals rliable's
    ``scipy.stats.trim_mean(x, 0.25)`` when the count is a multiple of 4; otherwise that one
    drops ``floor(n / 4)`` whole runs at each end and the two differ."""
    s = np.sort(np.asarray(samples, dtype=float), axis=-1)
    n = s.shape[-1]
    lo, hi = n / 4.0, 3.0 * n / 4.0
    edges = np.arange(n + 1, dtype=float)
    weight = np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, None)
    return (s * weight).sum(axis=-1) / (hi - lo)


def stratified_iqm(tasks: Sequence[Sequence[float]], rng: np.random.Generator | None = None,
                   n_resamples: int = N_RESAMPLES, level: float = LEVEL) -> Estimate:
    """The IQM of every run of every task, with a stratified bootstrap interval: each
    resample redraws the seeds within each task (every task keeps its seed count), as
    rliable does (Agarwal et al. 2021). Scores must be finite (normalise "never" first)."""
    arrays = [np.asarray(t, dtype=float) for t in tasks]
    if not arrays or any(a.size == 0 for a in arrays):
        raise ValueError("an IQM over tasks needs runs in every task")
    rng = generator() if rng is None else rng
    draws = [a[rng.integers(0, a.size, size=(n_resamples, a.size))] for a in arrays]
    lo, hi = percentile_interval(iqm(np.concatenate(draws, axis=1)), level)
    return Estimate(float(iqm(np.concatenate(arrays))), lo, hi)


def probability_of_improvement_tasks(xs: Sequence[Sequence[float | None]],
                                     ys: Sequence[Sequence[float | None]],
                                     rng: np.random.Generator | None = None,
                                     n_resamples: int = N_RESAMPLES, level: float = LEVEL,
                                     lower_is_better: bool = True) -> Estimate:
    """P(X better than Y) averaged over tasks (task k: :func:`probability_of_improvement`
    of its seeds), with a bootstrap that redraws each side's seeds within every task."""
    if len(xs) != len(ys) or not xs:
        raise ValueError("probability of improvement over tasks needs the same tasks")
    rng = generator() if rng is None else rng
    point, boot = 0.0, np.zeros(n_resamples)
    for x, y in zip(xs, ys, strict=True):
        worst = math.inf if lower_is_better else -math.inf
        xa, ya = as_values(x, worst), as_values(y, worst)
        if lower_is_better:
            xa, ya = -xa, -ya
        wins = _wins(xa, ya)
        n, m = wins.shape
        cx = rng.multinomial(n, np.full(n, 1.0 / n), size=n_resamples)
        cy = rng.multinomial(m, np.full(m, 1.0 / m), size=n_resamples)
        point += float(wins.mean())
        boot += np.einsum("bi,ij,bj->b", cx, wins, cy) / (n * m)
    k = len(xs)
    lo, hi = percentile_interval(boot / k, level)
    return Estimate(point / k, lo, hi)


def quantile(values: Sequence[float | None], q: float) -> float:
    """The q-quantile of ``values`` by one definition used everywhere in rnhql.

    Hyndman & Fan type 7 (numpy's and R's default): sort, take position
    h = (n - 1)·q, interpolate linearly between the values either side of h.
    ``None`` (never reached, G not reached) counts as +infinity and sorts last;
    interpolating towards it gives +infinity, landing exactly on a finite value
    gives that value. So a median of 10 seeds is the mean of the 5th and 6th
    values, and is ``never`` as soon as the 6th seed never got there.
    """
    arr = np.sort(as_values(values))
    if arr.size == 0:
        raise ValueError("quantile of no values")
    return _quantile_sorted(arr, q)


def _finite(v: float) -> float | None:
    return None if math.isinf(v) else v


def seed_stats(values: Sequence[float | None]) -> dict[str, Any]:
    """A figure over seeds as the summaries keep it: median, quartiles (:func:`quantile`)
    and the median's 95 % bootstrap interval (``ci95``, a fresh seeded generator per
    figure); ``None`` in and out means never / no G."""
    if not values:
        return {"median": None, "q25": None, "q75": None, "ci95": None}
    out: dict[str, Any] = {}
    for name, q in (("median", 0.5), ("q25", 0.25), ("q75", 0.75)):
        out[name] = _finite(quantile(values, q))
    out["ci95"] = [_finite(v) for v in bootstrap_ci(values, rng=generator())]
    return out

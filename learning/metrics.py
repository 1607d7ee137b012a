"""The figures that rank learners, each defined once.

Every summary, ranking, report and recording takes its figures from here, so a
figure means the same thing everywhere:

- reward per step over a window is a **ratio of sums** (total return / total
  steps). A mean of per-episode ratios lets a one-step episode that starts next
  to G (ratio ~100) outweigh hundreds of ordinary ones (ratio ~1).
- ``episodes_to_stable_optimal``: the first greedy test from which every later
  test, through the last, is optimal. A first hit (``episodes_to_first_optimal``)
  also counts a lucky test whose route is lost again later; it is kept as a
  secondary figure only.
- ``optimal_test_fraction``: the share of optimal tests over the last 10 % of
  tests (at least one): how settled the greedy route is at the end.
"""

from __future__ import annotations

import math

import numpy as np


def reward_per_step(returns: np.ndarray, steps: np.ndarray) -> float:
    """Total return / total steps over the episodes given (0 for no steps)."""
    total = float(np.sum(steps))
    return float(np.sum(returns)) / total if total > 0 else 0.0


def windowed_reward_per_step(returns: np.ndarray, steps: np.ndarray, window: int) -> np.ndarray:
    """Ratio of sums over the trailing ``window`` episodes, one value per episode.

    Entry i covers episodes ``max(0, i - window + 1) .. i`` (a shorter window at
    the start), computed from cumulative sums: O(n).
    """
    if window < 1:
        raise ValueError(f"window must be >= 1, got {window}")
    r = np.concatenate(([0.0], np.cumsum(np.asarray(returns, dtype=np.float64))))
    s = np.concatenate(([0.0], np.cumsum(np.asarray(steps, dtype=np.float64))))
    hi = np.arange(1, r.size)
    lo = np.maximum(hi - window, 0)
    total = s[hi] - s[lo]
    return np.divide(r[hi] - r[lo], total, out=np.zeros(hi.size), where=total > 0)


def _optimal(test_route_length: np.ndarray, optimal_length: int) -> np.ndarray:
    return np.asarray(test_route_length) == optimal_length


def episodes_to_first_optimal(test_episodes: np.ndarray, test_route_length: np.ndarray,
                              optimal_length: int) -> int | None:
    """Episodes trained at the first greedy test whose route has the optimal length."""
    hit = np.flatnonzero(_optimal(test_route_length, optimal_length))
    return int(np.asarray(test_episodes)[hit[0]]) if hit.size else None


def episodes_to_stable_optimal(test_episodes: np.ndarray, test_route_length: np.ndarray,
                               optimal_length: int) -> int | None:
    """Episodes trained at the first greedy test from which every later test is optimal.

    None when the last test is not optimal (or there are no tests).
    """
    ok = _optimal(test_route_length, optimal_length)
    if ok.size == 0 or not ok[-1]:
        return None
    bad = np.flatnonzero(~ok)
    first = 0 if bad.size == 0 else int(bad[-1]) + 1
    return int(np.asarray(test_episodes)[first])


def optimal_test_fraction(test_route_length: np.ndarray, optimal_length: int,
                          tail: float = 0.1) -> float | None:
    """Share of optimal greedy tests among the last ``tail`` of tests (at least one)."""
    ok = _optimal(test_route_length, optimal_length)
    if ok.size == 0:
        return None
    n = max(1, math.ceil(ok.size * tail))
    return float(np.mean(ok[-n:]))

"""A comparison's curves as a person reads them: per method one median line and its IQR.

Ninety per-seed series overlaid in one panel are a block of colour with a
legend of ninety entries. The comparison's default blueprint instead shows, per
method and in the method's colour, the median over seeds and the interquartile
band (q25 and q75 as thin lines of the same colour, left out of the legend) of:

- the greedy test from S, what the ranking reads: the share of seeds whose greedy route is
  optimal at the latest test (a share, not a median: its three rows are equal),
- steps per training episode (moving average over ``WINDOW`` episodes; training episodes
  start on random cells),
- success rate (share of the last ``WINDOW`` episodes that reached G),
- reward per step, as a ratio of sums over the last ``WINDOW`` episodes (total
  return / total steps: a mean of per-episode ratios is all spikes from short
  episodes that start next to G).

Quantiles across seeds are type 7 (``numpy.percentile``'s default), as in
``results.json``. Curves are decimated to every ``STRIDE``-th episode. The
per-seed curves stay in the file under each run (``runs/<label>/s<seed>``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import rerun as rr

from learning.metrics import windowed_reward_per_step
from scenarios.recording import scene

STRIDE = 10
WINDOW, FIGURES = scene.SUMMARY_WINDOW, scene.SUMMARY_FIGURES


def _moving_mean(y: np.ndarray, window: int) -> np.ndarray:
    c = np.concatenate(([0.0], np.cumsum(y, dtype=np.float64)))
    hi = np.arange(1, c.size)
    lo = np.maximum(hi - window, 0)
    return (c[hi] - c[lo]) / (hi - lo)


def greedy_optimal(rec: dict[str, Any], n: int) -> np.ndarray:
    """1.0 at each episode (1-based, the k-th value episode k + 1) whose latest greedy test
    from S found an optimal route, else 0.0 (0 before the first test)."""
    out = np.zeros(n)
    optimum = rec.get("optimal_route_length")
    for e, length in zip(rec.get("test_episodes", ()), rec.get("test_route_length", ()),
                         strict=True):
        if 1 <= e <= n:
            out[e - 1:] = float(length == optimum)
    return out


def run_curves(rec: dict[str, Any]) -> dict[str, np.ndarray]:
    """One run's curves, one value per episode, from its results.json record."""
    steps = np.asarray(rec["steps_per_episode"], dtype=np.float64)
    returns = np.asarray(rec["return_per_episode"], dtype=np.float64)
    success = np.asarray(rec["success_per_episode"], dtype=np.float64)
    return {"greedy": greedy_optimal(rec, steps.size),
            "steps": _moving_mean(steps, WINDOW), "success": _moving_mean(success, WINDOW),
            "reward_per_step": windowed_reward_per_step(returns, steps, WINDOW)}


def summary_curves(records: Sequence[dict[str, Any]], label_of: Any
                   ) -> dict[str, dict[str, np.ndarray]]:
    """{label: {figure: float64[4, m]}}: rows episode, q25, median, q75 (every STRIDE-th)."""
    groups: dict[str, list[dict[str, np.ndarray]]] = {}
    for rec in records:
        groups.setdefault(label_of(rec), []).append(run_curves(rec))
    out: dict[str, dict[str, np.ndarray]] = {}
    for label, curves in groups.items():
        n = min(len(c["steps"]) for c in curves)
        idx = np.unique(np.r_[np.arange(STRIDE - 1, n, STRIDE), n - 1])
        out[label] = {}
        for fig in FIGURES:
            y = np.stack([c[fig][:n] for c in curves])[:, idx]
            if fig == "greedy":  # a share of seeds: its rows are that share
                q25 = med = q75 = y.mean(axis=0)
            else:
                q25, med, q75 = np.percentile(y, [25, 50, 75], axis=0)
            out[label][fig] = np.stack([idx + 1.0, q25, med, q75])
    return out


def entity(fig: str, label: str, part: str = "") -> str:
    base = f"summary/{fig}/{rr.escape_entity_path_part(label)}"
    return f"{base}/{part}" if part else base


def log_summary(stream: rr.RecordingStream, curves: dict[str, dict[str, np.ndarray]]) -> None:
    """Send every method's curves (one ``send_columns`` per series) with their styles."""
    for label, figs in curves.items():
        colour = scene.label_colour(label)
        faded = tuple(int(0.55 * c + 0.45 * 255) for c in colour)
        for fig, arr in figs.items():
            episodes = arr[0].astype(np.int64)
            stream.log(entity(fig, label), rr.SeriesLines(colors=[colour], widths=[2.0],
                                                          names=[label]), static=True)
            stream.send_columns(entity(fig, label), indexes=[rr.TimeColumn(
                "episode", sequence=episodes)], columns=rr.Scalars.columns(scalars=arr[2]))
            for row, part in ((1, "q25"), (3, "q75")):
                stream.log(entity(fig, label, part), rr.SeriesLines(
                    colors=[faded], widths=[0.75], names=[label]), static=True)
                stream.send_columns(entity(fig, label, part), indexes=[rr.TimeColumn(
                    "episode", sequence=episodes)], columns=rr.Scalars.columns(scalars=arr[row]))

"""A sweep that keeps of each run only what its summary reads, for studies whose runs are
many and large.

A run's record holds its greedy policy and its per-episode series: on a 512² map about
400 kB, and the held-out study's 512² half runs 1,260 of them (500 MB) to print a table
of a few numbers a run. :func:`run_sweep` here is :func:`scenarios.sweep.run.run_sweep`
with files that keep a run's summary fields (:data:`KEPT_FIELDS`): ``results.json`` and
``summary.md`` are written as a comparison writes them, each run cut down, so the
summary, and every table a study computes from it and from the runs' episodes, is the
same, and a study's folder is small enough to be kept and resumed elsewhere. ``--resume``
reads back kept records and a comparison's whole ones alike. Figures need the series, so
there are none.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from scenarios.runs.results import write_results
from scenarios.runs.spec import RunSpec
from scenarios.sweep import run as _run
from scenarios.sweep.resume_state import COMPARE_FIELDS, check_summary_fields, finished_compare

# the summary's fields, a physics run's final-policy grading (P(G) and the drives' means)
# and its robot time (the robot-time table of summary.md), and a warm start's grid rung
KEPT_FIELDS = ("key", *COMPARE_FIELDS, "final_policy", "robot_seconds", "pretrain")


def kept(rec: dict[str, Any]) -> dict[str, Any]:
    """A run's record cut down to its summary's fields."""
    return {k: rec[k] for k in KEPT_FIELDS if k in rec}


def _write_kept(specs: Sequence[RunSpec], runs: list[dict[str, Any]], out: Path
                ) -> dict[str, Any]:
    results = _run.assemble(specs, [kept(r) for r in runs])
    write_results(out, results, list(dict.fromkeys(s.method for s in specs)))
    return results


KEPT_FILES = _run.SweepFiles(_write_kept, keep=kept,
                             finished=functools.partial(finished_compare,
                                                        check=check_summary_fields),
                             check=check_summary_fields)


def run_sweep(specs: Sequence[RunSpec], out_dir: Path,
              execute: Callable[..., list[dict[str, Any]]], resume: bool = False,
              figures: bool = False, **execute_kwargs: Any) -> dict[str, Any]:
    """:func:`scenarios.sweep.run.run_sweep` keeping :data:`KEPT_FIELDS` of each run."""
    if figures:
        raise ValueError("a sweep that keeps only the summary's fields draws no figures")
    return _run.run_sweep(specs, out_dir, execute, resume=resume, files=KEPT_FILES,
                          **execute_kwargs)

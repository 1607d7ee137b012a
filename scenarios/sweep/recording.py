"""A sweep's comparison recording: every run records a part file under ``<record>.parts/``,
merged at the end (or, after an interruption, of the runs finished so far) into one
``.rrd`` with a comparison blueprint. :func:`scenarios.sweep.run.run_sweep`
owns when; this module owns how.
"""

from __future__ import annotations

import dataclasses
import shutil
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from scenarios.runs.spec import RecordOptions, RunSpec, load


def run_label(spec: RunSpec, worlds: set[str]) -> str:
    """A run's name in a comparison recording: the method, plus the world if several."""
    return spec.method if len(worlds) == 1 else f"{spec.method}-{spec.world}"


@dataclass(frozen=True)
class SweepRecording:
    """A sweep's comparison recording: every run records a part file, merged at the end
    into one ``.rrd`` with a comparison blueprint."""

    path: str  # the .rrd to write
    every: int = 100  # episodes recorded in full per run: the first, every N-th, the last
    values_every: int = 300  # value heat maps every K episodes [episodes]
    detail_seeds: int = 1  # seeds per method and world recorded in full (others: curves)


def with_recording(specs: Sequence[RunSpec], recording: SweepRecording) -> list[RunSpec]:
    """Each run records a part file under ``<record>.parts/`` in its own subtree.

    The first ``detail_seeds`` seeds of each method and world are recorded in
    full; the others record their curves only. A 90-run comparison recorded in
    full is >100 MB, more than the viewer draws comfortably, and the comparison
    blueprint shows each method's first seed on the map anyway.
    """
    # lazy: scenarios.recording (rerun) costs 270 ms; a sweep without --record never needs it
    from scenarios.recording.recorder import run_prefix

    record = recording.path
    parts = Path(record + ".parts")
    if parts.is_symlink():  # the tool's own folder: a link planted there is removed
        parts.unlink()
    parts.mkdir(parents=True, exist_ok=True)
    # the same sweep gets the same id, so the parts of an interrupted run and of its
    # --resume are one recording in the viewer
    rid = str(uuid.uuid5(uuid.NAMESPACE_URL,
                         f"rnhql:{Path(record).resolve()}|{'|'.join(s.key for s in specs)}"))
    worlds = {s.world for s in specs}
    first_seeds = sorted({s.seed for s in specs})[:recording.detail_seeds]
    out = []
    for s in specs:
        label = run_label(s, worlds)
        out.append(dataclasses.replace(s, recording=RecordOptions(
            str(parts / f"{label}-s{s.seed}.rrd"), every=recording.every,
            values_every=recording.values_every, detail=s.seed in first_seeds,
            prefix=run_prefix(label, s.seed), recording_id=rid)))
    return out


def gather_parts(specs: Sequence[RunSpec], record: str, keep_parts: bool = False,
                 records: Sequence[dict[str, Any]] = ()) -> Path:
    """Merge the runs' part files into one recording with a comparison blueprint.

    ``keep_parts`` (an interrupted sweep): the recording holds the runs finished
    so far, and the parts stay for ``--resume`` to gather them all at the end.
    """
    # lazy: scenarios.recording (rerun) costs 270 ms; a sweep without --record never needs it
    from scenarios.recording.comparison import gather_comparison

    worlds = {s.world for s in specs}
    sc, model = load(*specs[0].problem)
    parts = [Path(s.recording.path) for s in specs
             if s.recording is not None and s.recording.detail
             and Path(s.recording.path).exists()]
    runs = [(run_label(s, worlds), s.seed) for s in specs]
    curves = None
    curve_runs = []
    if records:
        # lazy: as gather_comparison above
        from scenarios.recording.summary import summary_curves

        by_key = {s.key: s for s in specs}
        curves = summary_curves([r for r in records if r["key"] in by_key],
                                lambda r: run_label(by_key[r["key"]], worlds))
        record_of = {r["key"]: r for r in records}
        curve_runs = [(run_label(s, worlds), record_of[s.key]) for s in specs
                      if s.recording is not None and not s.recording.detail
                      and s.key in record_of]
    rid = next((s.recording.recording_id for s in specs if s.recording is not None), None)
    out = gather_comparison(record, parts, sc, runs, recording_id=rid, curves=curves,
                            model=model, curve_runs=curve_runs)
    if not keep_parts:
        shutil.rmtree(record + ".parts", ignore_errors=True)
    return out



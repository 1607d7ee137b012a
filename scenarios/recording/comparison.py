"""Comparisons (methods x seeds) in one recording; see :mod:`scenarios.recording.recorder`.

Each run logs under its own subtree ``runs/<method>/s<seed>`` (:func:`run_prefix`).

* One process: open one :class:`~scenarios.recording.RecordingFile`, create a
  recorder per run with ``file=f, prefix=run_prefix(m, s), blueprint=False``,
  and send :func:`~scenarios.recording_scene.comparison_blueprint` once.
* Worker processes (``rnhql compare`` runs seeds in a pool): every worker
  records ``<out>.parts/<method>-s<seed>.rrd`` with the shared ``recording_id``
  and ``blueprint=False``; the parent calls :func:`gather_comparison`, which
  adds a header (comparison table + blueprint) and merges everything with
  ``rerun rrd merge`` into one ``.rrd``. Parts with the same recording id also
  open together in the viewer (``rerun parts/*.rrd``) without merging.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import rerun as rr

from scenarios.recording.recorder import RecordingFile, run_prefix, scene
from sim.scenario import Scenario


def _log_header(stream: rr.RecordingStream, scenario: Scenario, runs: Sequence[tuple[str, int]],
                curves: dict | None) -> None:
    table = "\n".join(f"| {m} | {s} | `{run_prefix(m, s)}` |" for m, s in runs)
    stream.log("meta", rr.TextDocument(
        f"# rnhql comparison on {scenario.name}\n\n| method | seed | subtree |\n"
        f"|---|---|---|\n{table}\n", media_type="text/markdown"), static=True)
    if curves:
        from scenarios.recording.summary import log_summary

        log_summary(stream, curves)
    stream.send_blueprint(scene.comparison_blueprint(runs, scenario, run_prefix),
                          make_active=True, make_default=True)


def gather_comparison(out: str | Path, parts: Sequence[str | Path], scenario: Scenario,
                      runs: Sequence[tuple[str, int]], *, recording_id: str,
                      application_id: str = "rnhql", curves: dict | None = None) -> Path:
    """Header (blueprint, summary curves) first, then every run's part: one ``.rrd``.

    The order matters: the web viewer reads a file front to back and draws the
    curve panels from the summary, so the summary comes first and the curves show
    while the runs' detail is still loading. (``rerun rrd merge`` would order chunks
    by creation time and put the summary, made last, at the very end.) Each part is
    re-logged into this recording with ``log_file_from_path``, which keeps its
    chunks. The parts are left in place.
    """
    out = Path(out)
    with RecordingFile(out, application_id=application_id, recording_id=recording_id,
                       recording_name=f"{scenario.name} · compare") as f:
        _log_header(f.stream, scenario, runs, curves)
        f.stream.flush()
        for part in parts:
            f.stream.log_file_from_path(part)
        f.stream.flush()
    return out

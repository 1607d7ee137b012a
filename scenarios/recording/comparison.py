"""Comparisons (methods x seeds) in one recording; see :mod:`scenarios.recording.recorder`.

Each run logs under its own subtree ``runs/<method>/s<seed>`` (:func:`run_prefix`).

* One process: open one :class:`~scenarios.recording.RecordingFile`, create a
  recorder per run with ``file=f, prefix=run_prefix(m, s), blueprint=False``,
  and send :func:`~scenarios.recording.blueprint.comparison_blueprint` once.
* Worker processes (``rnhql compare`` runs seeds in a pool): every run recorded in
  full records ``<out>.parts/<method>-s<seed>.rrd`` with the shared
  ``recording_id`` and ``blueprint=False``; a curves-only run records nothing, its
  record carries its curves. The parent calls :func:`gather_comparison`, which
  writes a header (comparison table + summary curves + blueprint), re-logs every
  part, and logs the curves-only runs' curves from their records: one ``.rrd``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr

from scenarios.recording import blueprint
from scenarios.recording.recorder import Recorder, RecordingFile, run_prefix, scene
from scenarios.recording.summary import log_summary
from sim.grid import TabularModel
from sim.scenario import Scenario


def comparison_properties(scenario: Scenario, runs: Sequence[tuple[str, int]],
                          curve_runs: Sequence[tuple[str, dict]] = (),
                          given: dict[str, Any] | None = None) -> dict[str, Any]:
    """A comparison's recording properties (as a run's, :func:`scene.run_properties`, so one
    filter finds both): what it compares; ``given`` adds or overrides fields (the world and
    fidelity, which only the sweep knows for sure)."""
    labels = list(dict.fromkeys(m for m, _ in runs))
    worlds = sorted({lab.rsplit("-", 1)[1] for lab in labels
                     if lab.endswith(("-grid", "-physics"))}
                    | {r.get("world") for _, r in curve_runs if r.get("world")})
    props: dict[str, Any] = {
        "kind": "comparison", "scenario": scenario.name, "methods": ", ".join(labels),
        "seeds": len({s for _, s in runs}), "runs": len(runs),
        "rewards": scenario.rewards.scheme, "version": scene.versions()["rnhql"]}
    if worlds:
        props["world"] = ", ".join(worlds)
    props.update(given or {})
    return props


def _log_header(stream: rr.RecordingStream, scenario: Scenario, runs: Sequence[tuple[str, int]],
                curves: dict | None, properties: dict[str, Any]) -> None:
    table = "\n".join(f"| {m} | {s} | `{run_prefix(m, s)}` |" for m, s in runs)
    stream.log("meta", rr.TextDocument(
        f"# rnhql comparison on {scenario.name}\n\n| method | seed | subtree |\n"
        f"|---|---|---|\n{table}\n", media_type="text/markdown"), static=True)
    stream.send_property("rnhql", rr.AnyValues(**properties))
    key = None
    if curves:
        log_summary(stream, curves)
        key = scene.log_comparison_key(stream, list(curves))
    stream.send_blueprint(blueprint.comparison_blueprint(runs, scenario, run_prefix, key),
                          make_active=True, make_default=True)


def log_curves_of(file: RecordingFile, scenario: Scenario, model: TabularModel, label: str,
                  record: dict) -> None:
    """A curves-only run's per-seed curves, from its results.json record, under its subtree:
    what it would have logged itself (every 10th episode), without a stream of its own."""
    rec = Recorder.create(None, scenario, model, method=record["method"],
                          config=record.get("config", {}), seed=int(record["seed"]),
                          world=record.get("world", "grid"), fidelity=record.get("fidelity"),
                          prefix=run_prefix(label, int(record["seed"])), file=file,
                          blueprint=False, with_scene=False)
    steps = np.asarray(record["steps_per_episode"])
    rec.log_episode_metrics(np.arange(len(steps)), steps,
                            np.asarray(record["success_per_episode"]),
                            np.asarray(record["return_per_episode"]),
                            wall_time_s=np.asarray(record["wall_time_per_episode_s"]))
    rec.close()


def gather_comparison(out: str | Path, parts: Sequence[str | Path], scenario: Scenario,
                      runs: Sequence[tuple[str, int]], *, recording_id: str,
                      application_id: str = "rnhql", curves: dict | None = None,
                      model: TabularModel | None = None,
                      curve_runs: Sequence[tuple[str, dict]] = (),
                      properties: dict[str, Any] | None = None) -> Path:
    """Header (blueprint, summary curves) first, then every run's part: one ``.rrd``.

    The order matters: the web viewer reads a file front to back and draws the
    curve panels from the summary, so the summary comes first and the curves show
    while the runs' detail is still loading. (``rerun rrd merge`` would order chunks
    by creation time and put the summary, made last, at the very end.) Each part is
    re-logged into this recording with ``log_file_from_path``, which keeps its
    chunks. The parts are left in place. ``curve_runs`` ((label, record) pairs, with
    ``model``): runs recorded as curves only, logged here from their records.
    ``properties``: recording properties beyond those :func:`comparison_properties` finds.
    """
    out = Path(out)
    with RecordingFile(out, application_id=application_id, recording_id=recording_id,
                       recording_name=f"{scenario.name} · compare") as f:
        _log_header(f.stream, scenario, runs, curves,
                    comparison_properties(scenario, runs, curve_runs, properties))
        f.stream.flush()
        for part in parts:
            f.stream.log_file_from_path(part)
        for label, record in curve_runs:
            log_curves_of(f, scenario, model, label, record)
        f.stream.flush()
    return out

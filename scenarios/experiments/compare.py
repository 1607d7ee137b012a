"""``rnhql compare``: methods x seeds (x worlds) on one scenario -> results, summary, figures.

Partial progress survives: every finished run is appended to
``DIR/runs.partial.jsonl`` as it arrives, and ``--resume DIR`` skips the runs
whose key is already there. ``results.json`` is written (atomically) only
when the sweep is complete.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

from scenarios.runs.outdir import check_out_dir, sweep_lock
from scenarios.runs.results import RESULTS_VERSION, summarise, write_results
from scenarios.runs.spec import RunSpec, load

ALL_METHODS = ("rnh-ql", "rnh-ql+", "st-ql", "rn-ql", "pfh-rl", "sarsa-rs", "haql", "q-opt",
               "q-lambda", "dyna-q")
PARTIAL = "runs.partial.jsonl"


def version() -> str:
    try:
        return metadata.version("rnhql")
    except metadata.PackageNotFoundError:  # running from a source tree
        return "0+unknown"


Overrides = tuple[tuple[str, float], ...]


def make_specs(scenario: str, methods: Sequence[str], seeds: Sequence[int], episodes: int,
               worlds: Sequence[str], overrides: Overrides | dict[str, Overrides] = (),
               start=None, goal=None, drive_final: bool = False,
               rewards: str | None = None, fidelity: str | None = None) -> list[RunSpec]:
    """One spec per world x method x seed; ``overrides`` for all methods, or per method."""
    def of(m: str) -> Overrides:
        return overrides.get(m, ()) if isinstance(overrides, dict) else overrides

    return [RunSpec(scenario=scenario, method=m, seed=s, episodes=episodes, world=w,
                    overrides=of(m), start=start, goal=goal, drive_final=drive_final,
                    rewards=rewards, fidelity=fidelity if w == "physics" else None)
            for w in worlds for m in methods for s in seeds]


def run_label(spec: RunSpec, worlds: set[str]) -> str:
    """A run's name in a comparison recording: the method, plus the world if several."""
    return spec.method if len(worlds) == 1 else f"{spec.method}-{spec.world}"


def with_recording(specs: Sequence[RunSpec], record: str, every: int,
                   values_every: int = 300, detail_seeds: int = 1) -> list[RunSpec]:
    """Each run records a part file under ``<record>.parts/`` in its own subtree.

    The first ``detail_seeds`` seeds of each method and world are recorded in
    full; the others record their curves only. A 90-run comparison recorded in
    full is >100 MB, more than the viewer draws comfortably, and the comparison
    blueprint shows each method's first seed on the map anyway.
    """
    import dataclasses
    import uuid

    from scenarios.recording.recorder import run_prefix

    parts = Path(record + ".parts")
    parts.mkdir(parents=True, exist_ok=True)
    # the same sweep gets the same id, so the parts of an interrupted run and of its
    # --resume are one recording in the viewer
    rid = str(uuid.uuid5(uuid.NAMESPACE_URL,
                         f"rnhql:{Path(record).resolve()}|{'|'.join(s.key for s in specs)}"))
    worlds = {s.world for s in specs}
    first_seeds = sorted({s.seed for s in specs})[:detail_seeds]
    out = []
    for s in specs:
        label = run_label(s, worlds)
        out.append(dataclasses.replace(
            s, record_path=str(parts / f"{label}-s{s.seed}.rrd"), record_every=every,
            record_values_every=values_every, record_detail=s.seed in first_seeds,
            record_prefix=run_prefix(label, s.seed), recording_id=rid))
    return out


def gather_parts(specs: Sequence[RunSpec], record: str, keep_parts: bool = False,
                 records: Sequence[dict[str, Any]] = ()) -> Path:
    """Merge the runs' part files into one recording with a comparison blueprint.

    ``keep_parts`` (an interrupted sweep): the recording holds the runs finished
    so far, and the parts stay for ``--resume`` to gather them all at the end.
    """
    import shutil

    from scenarios.recording.comparison import gather_comparison

    worlds = {s.world for s in specs}
    sc, _ = load(*specs[0].problem)
    parts = [Path(s.record_path) for s in specs if s.record_path and Path(s.record_path).exists()]
    runs = [(run_label(s, worlds), s.seed) for s in specs]
    curves = None
    if records:
        from scenarios.recording.summary import summary_curves

        by_key = {s.key: s for s in specs}
        curves = summary_curves([r for r in records if r["key"] in by_key],
                                lambda r: run_label(by_key[r["key"]], worlds))
    out = gather_comparison(record, parts, sc, runs, recording_id=specs[0].recording_id,
                            curves=curves)
    if not keep_parts:
        shutil.rmtree(record + ".parts", ignore_errors=True)
    return out


def assemble(specs: Sequence[RunSpec], runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The results.json payload for finished runs, in spec order."""
    spec0 = specs[0]
    sc, model = load(*spec0.problem)
    order = {s.key: i for i, s in enumerate(specs)}
    runs = sorted(runs, key=lambda r: order.get(r["key"], len(order)))
    worlds = sorted({s.world for s in specs}, key=["grid", "physics"].index)
    rw = sc.rewards
    return {
        "version": RESULTS_VERSION,
        "rnhql_version": version(),
        "scenario": {"name": sc.name, "source": sc.source, "size_cells": [sc.nx, sc.ny],
                     "start": list(sc.start), "goal": list(sc.goal),
                     "rewards": {"scheme": getattr(rw, "scheme", "custom"), "goal": rw.goal,
                                 "bump": rw.bump, "step": rw.step}},
        "world": ",".join(worlds),
        "fidelity": next((s.fidelity_spec.label for s in specs if s.world == "physics"), None),
        "episodes": spec0.episodes,
        "overrides": {s.method: {k: v for k, v in s.overrides} for s in specs if s.overrides},
        "optimal_route_length": model.optimal_route_length,
        "runs": runs,
        "summary": summarise(runs),
    }


def read_partial(out_dir: Path) -> dict[str, dict[str, Any]]:
    """Finished runs of an interrupted sweep, by key (a torn last line is ignored)."""
    path = out_dir / PARTIAL
    done: dict[str, dict[str, Any]] = {}
    if path.exists():
        for line in path.read_text(encoding="utf-8").splitlines():
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue
            done[rec["key"]] = rec
    return done


def run_sweep(specs: Sequence[RunSpec], out_dir: Path,
              execute: Callable[..., list[dict[str, Any]]], resume: bool = False,
              figures: bool = True, **execute_kwargs: Any) -> dict[str, Any]:
    """Run the specs not finished yet with ``execute`` (a backend), then write everything.

    On Ctrl-C the runs finished so far are in ``runs.partial.jsonl`` and the
    ``KeyboardInterrupt`` propagates; ``resume=True`` later runs only the rest
    and writes the same ``results.json`` as an uninterrupted sweep.
    """
    check_out_dir(out_dir)
    with sweep_lock(out_dir):
        return _run_sweep(specs, out_dir, execute, resume, figures, **execute_kwargs)


def _run_sweep(specs: Sequence[RunSpec], out_dir: Path,
               execute: Callable[..., list[dict[str, Any]]], resume: bool, figures: bool,
               **execute_kwargs: Any) -> dict[str, Any]:
    from scenarios.figures.plots import all_figures

    done = read_partial(out_dir) if resume else {}
    keys = {s.key for s in specs}
    foreign = [k for k in done if k not in keys]
    if foreign:
        from scenarios.runs.outdir import OutDirError

        raise OutDirError(str(out_dir), "--resume",
                          f"holds {len(foreign)} finished run(s) of another sweep (e.g. "
                          f"{foreign[0]})", "resume with the same scenario, methods, seeds, "
                          "episodes and settings, use a new --out, or drop --resume")
    if not resume:
        (out_dir / PARTIAL).unlink(missing_ok=True)
    todo = [s for s in specs if s.key not in done]
    with open(out_dir / PARTIAL, "a", encoding="utf-8") as partial:
        def save(rec: dict[str, Any]) -> None:
            at = partial.tell()
            try:
                partial.write(json.dumps(rec) + "\n")
                partial.flush()
            except OSError:  # a full disk: never leave half a line for --resume to read
                with contextlib.suppress(OSError):
                    partial.truncate(at)
                raise

        new = execute(todo, on_result=save, **execute_kwargs) if todo else []
    progress = execute_kwargs.get("progress")
    if progress is not None:  # nothing left to run: its heartbeat must not outlive the sweep
        progress.close()
    results = assemble(specs, [*done.values(), *new])
    write_results(out_dir, results, list(dict.fromkeys(s.method for s in specs)))
    if figures:
        sc, model = load(*specs[0].problem)
        all_figures(results, sc, model, out_dir)
    (out_dir / PARTIAL).unlink(missing_ok=True)
    return results

"""``rnhql compare``: methods x seeds (x worlds) on one scenario -> results, summary, figures,
and a comparison recording.

:func:`run_sweep` is the one owner of a sweep's outputs: it runs the specs, writes
``results.json``, ``summary.md`` and the figures (or a study's own files, given its
:class:`SweepFiles`), and (given a :class:`SweepRecording`) merges the runs'
recordings into one ``.rrd``; every experiment and the CLI make this one call.

Partial progress survives: every finished run is appended to
``DIR/runs.partial.jsonl`` as it arrives, and ``--resume --out DIR`` skips the runs
whose key is already there. ``results.json`` is written (atomically) only
when the sweep is complete; after Ctrl-C the recording holds the runs finished so far.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import functools
import json
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

from scenarios.figures.plots import all_figures
from scenarios.runs import physics_grading as g
from scenarios.runs.physics import StopFlag
from scenarios.runs.results import RESULTS_VERSION, summarise, write_results
from scenarios.runs.spec import RunSpec, load
from scenarios.signals import sigint_handled_by
from scenarios.sweep.disk_full import disk_full_error
from scenarios.sweep.outdir import OutDirError, check_out_dir, sweep_lock
from scenarios.sweep.recording import (
    SweepRecording,
    gather_parts,
    run_label,
    with_recording,
)
from scenarios.sweep.resume_state import (
    PARTIAL,
    Finished,
    ResumeStateError,
    check_out_files,
    finished_compare,
    read_partial,
)
from scenarios.sweep.stop import (
    finishing,
    interrupted,
    keep_finished,
    merge_stopped,
    removed_if_left_empty,
)
from sim.files import open_own_file
from sim.physics.fidelity import Fidelity
from sim.physics.models.build import stochastic_model
from sim.physics.models.solve import solve
from sim.physics.models.stochastic_rollouts import ABS_TOL, P_TOL, REL_TOL

__all__ = ["PARTIAL", "SweepRecording", "finished_compare", "gather_parts", "interrupted",
           "make_specs", "read_partial", "run_label", "run_sweep", "with_recording"]


def version() -> str:
    try:
        return metadata.version("rnhql")
    except metadata.PackageNotFoundError:  # running from a source tree
        return "0+unknown"


Overrides = tuple[tuple[str, float], ...]


def make_specs(scenario: str, methods: Sequence[str], seeds: Sequence[int], episodes: int,
               worlds: Sequence[str], overrides: Overrides | dict[str, Overrides] = (),
               start=None, goal=None, drive_final: bool = False,
               rewards: str | None = None, fidelity: Fidelity | str | None = None,
               s_starts: float | None = None) -> list[RunSpec]:
    """One spec per world x method x seed; ``overrides`` for all methods, or per method."""
    def of(m: str) -> Overrides:
        return overrides.get(m, ()) if isinstance(overrides, dict) else overrides

    return [RunSpec(scenario=scenario, method=m, seed=s, episodes=episodes, world=w,
                    overrides=of(m), start=start, goal=goal, drive_final=drive_final,
                    rewards=rewards, fidelity=fidelity if w == "physics" else None,
                    s_starts=s_starts)
            for w in worlds for m in methods for s in seeds]


def assemble(specs: Sequence[RunSpec], runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The results.json payload for finished runs, in spec order."""
    spec0 = specs[0]
    sc, model = load(*spec0.problem)
    order = {s.key: i for i, s in enumerate(specs)}
    runs = sorted(runs, key=lambda r: order.get(r["key"], len(order)))
    worlds = sorted({s.world for s in specs}, key=["grid", "physics"].index)
    rw = sc.rewards
    phys = next((s for s in specs if s.world == "physics"), None)
    optimum = (optimum_at_fidelity(sc, phys.fidelity_spec)
               if phys is not None and not phys.fidelity_spec.is_exact else None)
    if optimum is not None:
        for r in runs:
            if r["world"] == "physics" and r.get("final_policy"):
                r["optimal_at_fidelity"] = matches_optimum(r["final_policy"], optimum)
    return {
        "version": RESULTS_VERSION,
        "rnhql_version": version(),
        "scenario": {"name": sc.name, "source": sc.source, "size_cells": [sc.nx, sc.ny],
                     "start": list(sc.start), "goal": list(sc.goal),
                     "rewards": {"scheme": getattr(rw, "scheme", "custom"), "goal": rw.goal,
                                 "bump": rw.bump, "step": rw.step},
                     "s_start_share": sc.s_start_share},
        "world": ",".join(worlds),
        "fidelity": next((s.fidelity_spec.label for s in specs if s.world == "physics"), None),
        "fidelity_knobs": next((fidelity_knobs(s.fidelity_spec) for s in specs
                                if s.world == "physics" or s.drive_final), None),
        "physics_grading": next((grading_protocol(s.fidelity_spec) for s in specs
                                 if s.world == "physics" or s.drive_final), None),
        "optimum_at_fidelity": optimum,
        "episodes": spec0.episodes,
        "overrides": {s.method: {k: v for k, v in s.overrides} for s in specs if s.overrides},
        "optimal_route_length": model.optimal_route_length,
        "runs": runs,
        "summary": summarise(runs),
    }


def optimum_at_fidelity(sc: Any, fid: Any) -> dict[str, Any] | None:
    """V* at the fidelity (:mod:`sim.physics.models.solve`; built once per scenario and
    fidelity, cached on disk): the yardstick "optimal at F" is measured against.
    ``RNHQL_NO_OPTIMUM=1`` skips it (tiny test sweeps)."""
    if os.environ.get("RNHQL_NO_OPTIMUM") == "1" or fid.hidden_state:
        return None  # hidden state (open loop, localisation): no V* (Fidelity.hidden_state)

    return optimum_record(solve(stochastic_model(sc, fid), sc.steps_per_episode).start)


def optimum_record(opt: Any) -> dict[str, Any]:
    """V* from S (:class:`sim.physics.models.solve`'s start) as results.json holds it, with
    the tolerance "optimal at F" is judged within."""
    return {"expected_primitives": round(float(opt.expected_primitives), 4),
            "p_goal_within_budget": round(float(opt.p_goal_within_budget), 6),
            "budget": int(opt.budget),
            "tolerance": {"p_goal": P_TOL, "primitives_relative": REL_TOL,
                          "primitives_absolute": ABS_TOL}}


def matches_optimum(policy: dict[str, Any], optimum: dict[str, Any]) -> bool:
    """A final policy is optimal at F when its drives match V* within the model's stated
    tolerance: P(G) at least P*(G) - 0.05 and mean primitives at most V*(S) + max(1, 5 %)."""
    tol = optimum["tolerance"]
    v = optimum["expected_primitives"]
    prims = policy.get("primitives_mean")
    return bool(prims is not None
                and policy["p_goal"] >= optimum["p_goal_within_budget"] - tol["p_goal"]
                and prims <= v + max(tol["primitives_absolute"],
                                     tol["primitives_relative"] * v))


def fidelity_knobs(fid: Any) -> dict[str, Any]:
    """Every knob of a fidelity by name, with its unit in the name (``..._m``) or below."""
    return {f.name: getattr(fid, f.name) for f in dataclasses.fields(fid)}


def grading_protocol(fid: Any) -> dict[str, Any]:
    """How physics runs were graded (see :mod:`scenarios.runs.physics_grading`)."""
    if fid.is_exact:
        return {"tests": "greedy walk on the exact physics model", "final_rollouts": 1}
    return {"tests": "rollouts at the run's fidelity", "test_rollouts": g.TEST_ROLLOUTS,
            "test_budget_primitives": f"min(steps_per_episode, {g.TEST_BUDGET_FACTOR} x "
                                      f"optimum + {g.TEST_BUDGET_SLACK})",
            "final_rollouts": g.FINAL_ROLLOUTS, "p_goal_interval": "Wilson 95 %"}


Writer = Callable[[Sequence[RunSpec], list[dict[str, Any]], Path], dict[str, Any]]


@dataclass(frozen=True)
class SweepFiles:
    """What a sweep writes once every run is finished, and what it holds of each run until
    then. :func:`compare_files` is ``rnhql compare``'s; a study with files of its own (the
    RNH-QL+ ablation) gives its own and keeps everything else of :func:`run_sweep`."""

    # every run finished: write the sweep's files (atomically), return its results
    write: Writer
    # what of a finished run's record the sweep holds, in memory and in runs.partial.jsonl,
    # "key" included; None: all of it
    keep: Callable[[dict[str, Any]], dict[str, Any]] | None = None
    # the runs of a finished sweep in the directory, by key (--resume re-runs none of
    # them); None: those of its results.json
    finished: Finished | None = None
    # what each run read back from runs.partial.jsonl must hold (ValueError says what it
    # lacks); None: a comparison's whole record when ``finished`` is None, else nothing
    check: Callable[[dict[str, Any]], None] | None = None


def compare_files(figures: bool = True) -> SweepFiles:
    """``rnhql compare``'s files: ``results.json``, ``summary.md`` and (``figures``) the
    figures."""
    return SweepFiles(functools.partial(write_compare, figures=figures))


def write_compare(specs: Sequence[RunSpec], runs: list[dict[str, Any]], out_dir: Path,
                  figures: bool = True) -> dict[str, Any]:
    results = assemble(specs, runs)
    write_results(out_dir, results, list(dict.fromkeys(s.method for s in specs)))
    if figures:
        sc, model = load(*specs[0].problem)
        with ctrl_c_held():
            all_figures(results, sc, model, out_dir)
    return results


@contextlib.contextmanager
def ctrl_c_held() -> Iterator[None]:
    """A Ctrl-C while the block draws figures acts at its end (seconds); a second one at
    once. One while matplotlib builds its lazy parsers (pyparsing, on the first label) can
    leave them half made and surface as an AttributeError."""
    stop = StopFlag()
    with sigint_handled_by(stop.request):
        yield
    if stop.requested:
        raise KeyboardInterrupt


def run_sweep(specs: Sequence[RunSpec], out_dir: Path,
              execute: Callable[..., list[dict[str, Any]]], resume: bool = False,
              figures: bool = True, recording: SweepRecording | None = None,
              files: SweepFiles | None = None, **execute_kwargs: Any) -> dict[str, Any]:
    """Run the specs not finished yet with ``execute`` (a backend), then write everything:
    ``results.json``, ``summary.md``, the figures (``figures``) and the comparison
    recording (``recording``); or, given ``files``, what they write.

    On Ctrl-C the runs finished so far are in ``runs.partial.jsonl``, the recording
    holds them (its parts are kept for ``--resume``), a line on stderr says so, nothing
    ``--resume`` cannot use is left (:mod:`scenarios.sweep.stop`), and the
    ``KeyboardInterrupt`` propagates; ``resume=True`` later runs only the rest and
    writes the same ``results.json`` as an uninterrupted sweep.
    """
    with removed_if_left_empty(out_dir):  # by a stop before anything was kept in it
        check_out_dir(out_dir)
        check_out_files(out_dir)  # a folder named results.json fails now, not after every run
        files = files or compare_files(figures)
        if recording is not None:
            specs = with_recording(specs, recording)
        with sweep_lock(out_dir):
            results = _run_and_keep(specs, out_dir, execute, resume, files, recording,
                                    **execute_kwargs)
            if recording is not None:
                tail(execute_kwargs.get("progress"), f"merging the recording {recording.path}")
                try:
                    with finishing(recording.path):  # every run is done: the recording holds all
                        gather_parts(specs, recording.path, records=results["runs"])
                except KeyboardInterrupt:  # SIGTERM, SIGHUP: the parts stay for --resume
                    merge_stopped(recording.path)
                    raise
                except OSError as err:
                    if err.errno != errno.ENOSPC:
                        raise
                    raise _disk_full(err, out_dir, specs, recording, files, True) from None
    return results


def tail(progress: Any, what: str) -> None:
    """Name the work after the last run (seconds to a minute: figures, the recording's
    merge) on the progress stream, so the end of the bar is not followed by silence."""
    if progress is not None and getattr(progress, "enabled", False):
        print(f"{what}…", file=progress.stream, flush=True)


def _run_and_keep(specs: Sequence[RunSpec], out_dir: Path,
                  execute: Callable[..., list[dict[str, Any]]], resume: bool,
                  files: SweepFiles, recording: SweepRecording | None,
                  **execute_kwargs: Any) -> dict[str, Any]:
    """:func:`_run_sweep`; when it is stopped, what was finished is kept
    (:func:`~scenarios.sweep.stop.keep_finished`)."""
    try:
        return _run_sweep(specs, out_dir, execute, resume, files, **execute_kwargs)
    except KeyboardInterrupt:
        keep_finished(specs, out_dir, recording, files.finished)
        raise
    except ImportError as err:
        if not interrupted(err):
            raise
        # Ctrl-C inside a C extension's import (matplotlib's, while the figures are
        # drawn) surfaces as "ImportError: initialization failed": it is the same Ctrl-C
        keep_finished(specs, out_dir, recording, files.finished)
        raise KeyboardInterrupt from err
    except OSError as err:
        if err.errno != errno.ENOSPC:
            raise
        raise _disk_full(err, out_dir, specs, recording, files) from None


def _disk_full(err: OSError, out_dir: Path, specs: Sequence[RunSpec],
               recording: SweepRecording | None, files: SweepFiles,
               all_done: bool = False) -> OSError:
    """A full disk (:mod:`scenarios.sweep.disk_full`), counting the runs kept so far."""
    try:
        done = read_partial(out_dir, files.finished)
    except Exception:  # a torn resume file must not hide the full disk
        done = {}
    finished = sum(s.key in done for s in specs)
    return disk_full_error(err, out_dir, specs, None if recording is None else recording.path,
                           len(specs) if all_done else finished, all_done)


def _check_kept_runs(specs: Sequence[RunSpec], done: dict[str, dict[str, Any]],
                     out_dir: Path) -> None:
    """A kept run says what its key says: its ``method``, ``world`` and ``seed`` (where the
    record holds them) are the spec's. An edited name would otherwise be trusted by
    ``--resume`` and shown in the summary and figures as a method that never ran."""
    for spec in specs:
        rec = done.get(spec.key)
        if rec is None:
            continue
        for name in ("method", "world", "seed"):
            if name in rec and rec[name] != getattr(spec, name):
                raise ResumeStateError(
                    str(out_dir), "--resume", f"holds the run {spec.key} with {name} "
                    f"{rec[name]!r}, but that run's {name} is {getattr(spec, name)!r} (the "
                    "file was edited)", "remove that run from results.json or "
                    "runs.partial.jsonl (it is run again), or use a new --out")


def _run_sweep(specs: Sequence[RunSpec], out_dir: Path,
               execute: Callable[..., list[dict[str, Any]]], resume: bool, files: SweepFiles,
               **execute_kwargs: Any) -> dict[str, Any]:
    done = read_partial(out_dir, files.finished, files.check) if resume else {}
    keys = {s.key for s in specs}
    foreign = [k for k in done if k not in keys]
    if foreign:
        raise OutDirError(str(out_dir), "--resume",
                          f"holds {len(foreign)} finished run(s) of another sweep (e.g. "
                          f"{foreign[0]})", "resume with the same scenario, methods, seeds, "
                          "episodes and settings, use a new --out, or drop --resume")
    _check_kept_runs(specs, done, out_dir)
    if not resume:
        (out_dir / PARTIAL).unlink(missing_ok=True)
    todo = [s for s in specs if s.key not in done]
    if resume:
        print(f"resuming: {len(specs) - len(todo)} of {len(specs)} runs already finished in "
              f"{out_dir / PARTIAL}; running the other {len(todo)}", file=sys.stderr)
    progress = execute_kwargs.get("progress")
    if progress is not None and hasattr(progress, "expect"):
        progress.expect(len(todo), sum(s.episodes for s in todo),
                        sum(s.episodes for s in todo if s.world == "physics"))

    fd = open_own_file(out_dir / PARTIAL, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    with os.fdopen(fd, "a", encoding="utf-8") as partial:
        def save(rec: dict[str, Any]) -> None:
            at = partial.tell()
            try:
                partial.write(json.dumps(rec) + "\n")
                partial.flush()
            except OSError:  # a full disk: never leave half a line for --resume to read
                with contextlib.suppress(OSError):
                    partial.truncate(at)
                raise

        keep = {} if files.keep is None else {"keep": files.keep}
        new = execute(todo, on_result=save, **keep, **execute_kwargs) if todo else []
    if progress is not None:  # nothing left to run: its heartbeat must not outlive the sweep
        progress.close()
        tail(progress, "writing results.json, summary.md and the figures")
    results = files.write(specs, [*done.values(), *new], out_dir)
    (out_dir / PARTIAL).unlink(missing_ok=True)
    return results

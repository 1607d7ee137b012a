"""One call runs a sweep: :func:`sweep`, with the one choice of where (:func:`backend`).

:func:`scenarios.api.compare` and every study and bench run their specs through here, so the
local/Ray choice, the worker count's default (every core) and the progress line are
written once. With an output folder it is :func:`scenarios.sweep.run.run_sweep` (results,
summary, figures, the recording, ``resume``); without one the records come back and
nothing is written.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from scenarios.runs.spec import RunSpec
from scenarios.sweep import backends
from scenarios.sweep.backends import Progress
from scenarios.sweep.run import SweepFiles, SweepRecording, assemble, run_sweep

BACKENDS = ("local", "ray")
START_METHODS = (None, "fork", "spawn", "forkserver")


def default_jobs() -> int:
    """Worker processes when none are asked for: every core."""
    return os.cpu_count() or 1


def backend(name: str = "local", jobs: int | None = None, address: str | None = None,
            start_method: str | None = None) -> tuple[Callable[..., Any], dict[str, Any]]:
    """The executor of backend ``name`` and its keywords: a local process pool of ``jobs``
    workers (default every core), or Ray at ``address`` (None: a local runtime of ``jobs``
    CPUs). The arguments are the caller's to check (:func:`scenarios.api.compare`)."""
    if name == "local":
        # looked up per call: a test stands in for run_local
        return backends.run_local, {"jobs": jobs or default_jobs(),
                                    "start_method": start_method}
    if name == "ray":
        return backends.run_ray, {"address": address, "num_cpus": jobs}
    raise ValueError(f"backend {name!r}: use one of {BACKENDS}")


def sweep(specs: Sequence[RunSpec], out: str | Path | None = None, *, backend_name: str = "local",
          jobs: int | None = None, address: str | None = None,
          start_method: str | None = None, resume: bool = False, figures: bool = True,
          recording: SweepRecording | None = None, files: SweepFiles | None = None,
          progress: bool | Progress = True) -> dict[str, Any]:
    """Run ``specs``: the results payload (``results.json``'s; its ``runs`` in spec order).

    ``out``: the folder of results, summary and figures (``figures``), or ``files`` (what
    a study writes instead); ``resume``: keep the runs finished there. ``out=None``: nothing
    written, unless a ``recording`` needs a folder (a temporary one). ``progress``: a line
    on stderr (or a :class:`Progress` of the caller's)."""
    execute, kwargs = backend(backend_name, jobs, address, start_method)
    bar = progress if isinstance(progress, Progress) else Progress(len(specs),
                                                                   enabled=bool(progress))
    if out is None and recording is None:
        try:
            records = execute(specs, progress=bar, **kwargs)
        finally:
            bar.close()
        return assemble(specs, records)
    with _out_dir(out) as out_dir:
        return run_sweep(specs, out_dir, execute, resume=resume, recording=recording,
                         progress=bar, figures=figures and out is not None, files=files,
                         **kwargs)


@contextlib.contextmanager
def _out_dir(out: str | Path | None) -> Iterator[Path]:
    """``out``, or a folder that is gone afterwards (a recorded sweep with nothing to keep)."""
    if out is not None:
        yield Path(out)
        return
    with tempfile.TemporaryDirectory(prefix="rnhql-sweep-") as tmp:
        yield Path(tmp)

"""Where the runs of a sweep execute: a local process pool, or a Ray cluster.

A backend takes specs and returns their records in spec order; ``on_result``
sees each record as soon as it finishes so the caller can persist it; ``keep``
(optional) cuts each record down to what the caller holds (a long study keeps a few
figures of each run, not its per-episode arrays). Specs are
planned into tasks first (:func:`scenarios.runs.physics_batch.plan_tasks`): a grid
run is a task of its own, physics runs of one problem and budget are the robots of
one batch (a task that returns several records at once). A run
that fails (bad config, crashed worker) does not lose the others: the backend
finishes the rest and raises :class:`SweepError` naming every failed run's
parameters.
"""

from __future__ import annotations

import ctypes
import errno
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from learning.methods.registry import EXTERNAL, restore_external
from scenarios.runs import work
from scenarios.runs.physics_batch import plan_tasks
from scenarios.runs.run import run_task
from scenarios.runs.spec import RunSpec
from scenarios.signals import stop_signals_held
from sim.errors import InputError

OnResult = Callable[[dict[str, Any]], None] | None
Keep = Callable[[dict[str, Any]], dict[str, Any]] | None
END_WAIT_S = 5.0  # the pool's manager thread ends within this once its workers are gone [s]


class SweepError(RuntimeError):
    """Some runs failed; ``failures`` holds (spec, error message) pairs."""

    def __init__(self, failures: list[tuple[RunSpec, str]], finished: int) -> None:
        self.failures = failures
        lines = [f"{len(failures)} run(s) failed ({finished} finished and saved):"]
        lines += [f"  {spec.key}: {msg}" for spec, msg in failures]
        super().__init__("\n".join(lines))


class BackendError(InputError):
    """A backend that cannot start (e.g. Ray not installed)."""


class Progress:
    """Progress of a sweep on stderr (no dependency), measured in work: the episodes its
    runs have finished, in every worker process (:mod:`scenarios.runs.work`).

    On a terminal: a one-line bar, redrawn as work is done. Off a terminal (logs, CI,
    a notebook): a plain line every ``interval_s`` seconds while the sweep runs, and one
    when it ends. ``enabled=False`` silences both. The estimate of the time left is each
    world's episodes left over that world's rate of the last ``window_s`` seconds
    (:meth:`eta_s`), given only once episodes have been finishing for a few seconds: the
    first seconds of a sweep are compilation and loading, which no rate of runs finished
    can tell apart from work.
    """

    def __init__(self, total: int, enabled: bool | None = None, interval_s: float = 5.0,
                 stream: Any = None, window_s: float = 20.0) -> None:
        self.total, self.done, self.t0 = total, 0, time.perf_counter()
        self.episodes_total = self.physics_total = 0
        self._rates: dict[str, float] = {}  # the last rate measured per world [episodes/s]
        self.counter = work.new_counter()
        work.share(self.counter)  # runs in this process (--jobs 1) count here too
        self.window_s = window_s
        self._samples: list[tuple[float, int, int]] = []  # (time, grid, physics episodes)
        self.stream = sys.stderr if stream is None else stream
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = True if enabled is None else enabled
        self.bar = self.enabled and tty
        self.interval_s = interval_s
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        if self.enabled and total > 0:
            self._thread = threading.Thread(target=self._heartbeat, daemon=True,
                                            name="rnhql-progress")
            self._thread.start()

    def expect(self, runs: int, episodes: int, physics_episodes: int = 0) -> None:
        """The work this sweep will do (after ``--resume`` dropped what was finished):
        ``episodes`` in all, ``physics_episodes`` of them in the physics world."""
        with self._lock:
            self.total, self.episodes_total = runs, episodes
            self.physics_total = physics_episodes

    @property
    def episodes_done(self) -> int:
        return work.episodes(self.counter)

    def eta_s(self, now: float | None = None) -> float | None:
        """Seconds left, or None while too early to say.

        Each world is estimated from its own rate (a physics episode costs hundreds of grid
        episodes: one rate for both once called a mixed sweep half done after its grid runs),
        measured over the last ``window_s`` seconds once its episodes have flowed for a few
        seconds; the time left is the sum of each world's episodes left over its rate, and
        there is none until every world with work left has a rate. While a worker warms up
        (compiles a method's kernels, :func:`scenarios.runs.work.warm_up`) no rate is
        measured (a rate across a compile once gave an estimate 8x too long): before the
        first estimate there is none, after it the last rates carry the estimate through.
        """
        now = time.perf_counter() if now is None else now
        done = self.episodes_done
        physics = work.physics_episodes(self.counter)
        if work.warming(self.counter):
            self._samples.clear()
            return self._estimate(done - physics, physics)
        self._samples.append((now, done - physics, physics))
        while len(self._samples) > 2 and now - self._samples[1][0] >= self.window_s:
            self._samples.pop(0)
        for k, world in ((1, "grid"), (2, "physics")):
            flowing = [(smp[0], smp[k]) for smp in self._samples if smp[k] > 0]
            if len(flowing) < 2:
                continue
            (t_a, d_a), (t_b, d_b) = flowing[0], flowing[-1]
            if t_b - t_a >= min(3.0, self.window_s) and d_b > d_a:
                self._rates[world] = (d_b - d_a) / (t_b - t_a)
        return self._estimate(done - physics, physics)

    def _estimate(self, grid_done: int, physics_done: int) -> float | None:
        if not self.episodes_total:
            return None
        left = {"grid": self.episodes_total - self.physics_total - grid_done,
                "physics": self.physics_total - physics_done}
        total = 0.0
        for world, n in left.items():
            if n <= 0:
                continue
            if world not in self._rates:
                return None
            total += n / self._rates[world]
        return total

    def _line(self) -> str:
        elapsed = time.perf_counter() - self.t0
        eta = self.eta_s()
        left = "" if eta is None or self.done >= self.total else f", ~{eta:.0f} s left"
        if eta is None and self.done < self.total and work.warming(self.counter):
            left = ", compiling kernels (no estimate yet)"
        episodes = ""
        done = min(self.episodes_done, self.episodes_total)
        if self.episodes_total and (done or not self.done):  # runs elsewhere (Ray) count none
            episodes = (f"{done:,}/{self.episodes_total:,} episodes "
                        f"({100 * done / self.episodes_total:.0f} %), ")
        return (f"progress: {episodes}{self.done}/{self.total} runs done, {elapsed:.0f} s "
                f"elapsed{left}")

    def _heartbeat(self) -> None:
        every = min(self.interval_s, 1.0) if self.bar else self.interval_s
        while not self._stop.wait(every):
            with self._lock:
                if self._stop.is_set():  # closed while this beat waited for the lock:
                    return  # the closing line is the last one
                try:
                    if self.bar:
                        self.stream.write("\r" + self._line().ljust(100))
                    else:
                        self.stream.write(self._line() + "\n")
                    self.stream.flush()
                except (OSError, ValueError):  # the stream was closed under us: stop
                    return

    def update(self, label: str) -> None:
        with self._lock:
            self.done += 1
        if self.done >= self.total:
            self.close()

    def close(self) -> None:
        """Stop the heartbeat (its last line says where the sweep ended)."""
        if self._stop.is_set():
            return
        self._stop.set()
        if self._thread is not None:
            with self._lock:
                try:
                    end = "\r" + self._line().ljust(100) + "\n" if self.bar else self._line() + "\n"
                    self.stream.write(end)
                    self.stream.flush()
                except (OSError, ValueError):
                    pass


class _Collector:
    def __init__(self, specs: Sequence[RunSpec], on_result: OnResult,
                 progress: Progress | None, keep: Keep = None) -> None:
        self.specs, self.on_result, self.progress = specs, on_result, progress
        self.keep = keep
        self.records: list[dict[str, Any] | None] = [None] * len(specs)
        self.failures: list[tuple[RunSpec, str]] = []

    def ok(self, i: int, rec: dict[str, Any]) -> None:
        if self.keep is not None:
            rec = self.keep(rec)
        self.records[i] = rec
        if self.on_result is not None:
            self.on_result(rec)
        self._tick(i)

    def failed(self, i: int, exc: BaseException) -> None:
        full = disk_full_cause(exc, self.specs[i])
        if full is not None:  # every later run would fail the same way: stop the sweep now
            raise full
        self.failures.append((self.specs[i], f"{type(exc).__name__}: {exc}"))
        self._tick(i, " FAILED")

    def _tick(self, i: int, suffix: str = "") -> None:
        if self.progress is not None:
            sp = self.specs[i]
            self.progress.update(f"{sp.method} {sp.world} s{sp.seed}{suffix}")

    def result(self) -> list[dict[str, Any]]:
        done = [r for r in self.records if r is not None]
        if self.failures:
            raise SweepError(self.failures, len(done))
        return done


def _init_worker(counter: Any = None, parent: int | None = None,
                 external: dict[str, tuple[str, bool]] | None = None) -> None:
    """Pool worker initializer: the signals (:func:`_ignore_sigint`), the sweep's shared
    episode counter (:mod:`scenarios.runs.work`) and the methods the sweep's process
    registered from outside the package (``external``: a worker started by spawn or
    forkserver has only the built-in ones). ``parent``: the sweep's pid, to see whether it
    died before this worker could ask to die with it."""
    _ignore_sigint(parent)
    work.share(counter)
    if external:
        restore_external(external)


def disk_full_cause(exc: BaseException, spec: RunSpec) -> OSError | None:
    """The full disk behind a failed run, as an OSError naming the file (ENOSPC), or None.

    A run's own write error says so (errno ENOSPC). A pool worker that died (a
    ``BrokenProcessPool``: the real cause never reaches the parent) is put down to a full
    disk when the file system of the run's recording is full."""
    # looked up per call: tests/test_reliability2.py stands in for no_space_left
    from sim.files import no_space_left

    if isinstance(exc, OSError) and exc.errno == errno.ENOSPC:
        return exc
    if isinstance(exc, BrokenProcessPool) and spec.recording is not None and \
            no_space_left(spec.recording.path):
        return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), spec.recording.path)
    return None


def _ignore_sigint(parent: int | None = None) -> None:
    """Pool worker initializer: Ctrl-C (and SIGHUP) reaches the whole process group, but only
    the parent decides what happens (it keeps the finished runs and ends the workers itself). On
    Linux a worker is also killed when its parent dies (``PR_SET_PDEATHSIG``): a parent
    killed with SIGKILL would otherwise leave its workers running their runs (minutes) and
    holding its pipes. The signal is armed only from here on, so a parent killed between
    the fork and this line would go unnoticed: a worker whose parent is already gone
    (``getppid`` is no longer ``parent``) ends at once."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)  # a closed terminal: the parent's to handle
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover - no prctl: nothing to do
            pass
    if parent is not None and os.getppid() != parent:
        os._exit(1)  # orphaned before the death signal was armed


def _end_workers(pool: ProcessPoolExecutor) -> None:
    """Stop a pool now: drop queued runs, terminate the workers mid-run, and see the pool's
    manager thread end (the interpreter joins it on exit).

    ``shutdown(cancel_futures=True)`` alone still waits for the running tasks
    (minutes in a physics sweep); Python 3.11 has no public way to end the
    workers, so this reaches for the pool's process table. A worker ended while it was
    sending a finished run's record (hundreds of kB: many pipe-fulls) leaves the manager
    thread reading the rest of that message, and this process holds the result pipe's
    write end too, so that read would never end and the exit would hang joining the
    thread (a signalled sweep, now and then, on a loaded machine). Closing that end once the
    workers are gone ends the read (end of file: a broken pool, which it then cleans up).
    """
    processes = list((getattr(pool, "_processes", None) or {}).values())
    results = getattr(pool, "_result_queue", None)
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        proc.terminate()
    for proc in processes:
        proc.join(timeout=1.0)
        if proc.is_alive():
            proc.kill()
            proc.join(timeout=1.0)
    writer = getattr(results, "_writer", None)
    if writer is not None:
        writer.close()
    if manager is not None:
        manager.join(timeout=END_WAIT_S)


def run_local(specs: Sequence[RunSpec], jobs: int = 1, on_result: OnResult = None,
              progress: Progress | None = None, keep: Keep = None,
              start_method: str | None = None) -> list[dict[str, Any]]:
    """Run specs in ``jobs`` worker processes (in this process when ``jobs == 1``), started
    by ``start_method`` (``"fork"``, ``"spawn"``, ``"forkserver"``; None: Python's default).

    Ctrl-C (``KeyboardInterrupt`` in this process) ends the workers at once and
    propagates; every run finished before it has already gone to ``on_result``.
    """
    try:
        return _run_local(specs, jobs, _Collector(specs, on_result, progress, keep),
                          start_method)
    finally:
        if progress is not None:
            progress.close()


def _run_local(specs: Sequence[RunSpec], jobs: int, col: _Collector,
               start_method: str | None = None) -> list[dict[str, Any]]:
    tasks = plan_tasks(specs, max(jobs, 1))
    if jobs <= 1 or len(tasks) <= 1:
        for task in tasks:
            try:
                recs = run_task([specs[i] for i in task])
            except Exception as exc:  # keep going: report with its parameters at the end
                for i in task:
                    col.failed(i, exc)
            else:
                for i, rec in zip(task, recs, strict=True):
                    col.ok(i, rec)
        return col.result()
    counter = getattr(col.progress, "counter", None)
    context = None if start_method is None else multiprocessing.get_context(start_method)
    if context is not None and context.get_start_method() != "fork":
        counter = None  # a lock made for forked workers cannot reach spawned ones: runs
        #                 finished still count, episodes inside the workers do not
    pool = ProcessPoolExecutor(max_workers=jobs, initializer=_init_worker, mp_context=context,
                               initargs=(counter, os.getpid(), dict(EXTERNAL)))
    try:
        with stop_signals_held():  # the workers are forked here (see stop_signals_held)
            futures = {pool.submit(run_task, [specs[i] for i in task]): task for task in tasks}
        for fut in as_completed(futures):
            task = futures[fut]
            try:
                recs = fut.result()
            except Exception as exc:  # includes BrokenProcessPool from a crashed worker
                for i in task:
                    col.failed(i, exc)
            else:
                for i, rec in zip(task, recs, strict=True):
                    col.ok(i, rec)
    except BaseException:  # Ctrl-C (or a failing on_result): stop now, not after every run
        _end_workers(pool)
        raise
    pool.shutdown(wait=True)
    return col.result()


def run_ray(specs: Sequence[RunSpec], address: str | None = None, num_cpus: int | None = None,
            on_result: OnResult = None, progress: Progress | None = None,
            keep: Keep = None) -> list[dict[str, Any]]:
    """Run each task (a run, or a physics batch) as a Ray task (one CPU each) on a cluster
    or a local runtime.

    ``address``: ``None`` starts a local runtime (``num_cpus`` CPUs), ``"auto"``
    joins the cluster this machine belongs to, ``"ray://host:port"`` connects a
    client. Every node needs rnhql installed (``pip install rnhql[ray]``).
    """
    try:
        # optional (rnhql[ray]); 215 ms at import
        import ray
    except ImportError:
        raise BackendError("command line", "--backend ray", "Ray is not installed",
                           "pip install 'rnhql[ray]' (or pip install ray)") from None
    started_here = not ray.is_initialized()
    if started_here:
        ray.init(address=address, num_cpus=num_cpus if address is None else None,
                 include_dashboard=False, log_to_driver=False, configure_logging=False)
    try:
        remote = ray.remote(num_cpus=1, max_retries=1)(run_task)
        tasks = plan_tasks(specs, num_cpus or 1)
        refs = {remote.remote([specs[i] for i in task]): task for task in tasks}
        col = _Collector(specs, on_result, progress, keep)
        pending = list(refs)
        try:
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                task = refs[ready[0]]
                try:
                    recs = ray.get(ready[0])
                except Exception as exc:  # RayTaskError wraps the worker's exception
                    for i in task:
                        col.failed(i, getattr(exc, "cause", None) or exc)
                else:
                    for i, rec in zip(task, recs, strict=True):
                        col.ok(i, rec)
        except BaseException:  # Ctrl-C: cancel what is queued or running, keep what finished
            for ref in pending:
                ray.cancel(ref, force=True)
            raise
        return col.result()
    finally:
        if progress is not None:
            progress.close()
        if started_here:
            ray.shutdown()

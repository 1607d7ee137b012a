"""The ``rnhql`` command.

Every subcommand is a function ``cmd_<name>(args) -> int``. Input errors
(:class:`sim.errors.InputError` and its kin) are printed as one line and exit
with status 2; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import errno
import os
import signal
import sys
import threading
import time
from collections.abc import Sequence
from importlib.metadata import PackageNotFoundError, version
from typing import Any

from learning.drivers.checkpoint import CheckpointError
from learning.methods.registry import comparison_methods
from learning.plain.learner import LearnerError
from scenarios.cli import (
    bench,
    catalog,
    compare,
    models,
    report,
    route,
    train,
    view,
)
from scenarios.cli.args import (
    add_fidelity_arg,
    add_record_args,
    add_scenario_args,
    add_training_args,
    add_world_args,
)
from scenarios.sweep.backends import SweepError
from scenarios.sweep.outdir import RECORD_DEFAULT, check_empty_paths
from sim.errors import InputError


class _Parser(argparse.ArgumentParser):
    """Usage errors in one line (exit 2), like every other input error of the CLI."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message}. Fix: see {self.prog} --help\n")


class _Help(argparse.HelpFormatter):
    """Every flag's line ends with its default, unless the help already names it."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        if "\n" in text:  # an epilog laid out by hand (methods, examples): keep its lines
            return "\n".join(indent + line for line in text.splitlines())
        return super()._fill_text(text, width, indent)

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        d = action.default
        if ("default" in text or d is None or d is False or d == argparse.SUPPRESS
                or (action.option_strings == [] and action.nargs is None)):
            return text
        return f"{text} (default: {d})"


def _methods_epilog(examples: str) -> str:
    """A subcommand's help ends with the methods it can run and examples."""
    return (f"methods: {', '.join(comparison_methods())} (docs/methods.md)\n\n"
            f"examples:\n  {examples}")


def _version() -> str:
    """The installed package's version (what results.json records)."""
    try:
        return version("rnhql")
    except PackageNotFoundError:
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="rnhql", formatter_class=_Help,
        description="Route searching with RBF-network heuristic Q-learning (RNH-QL) and its "
                    "baselines, on a grid and in a Pymunk physics world.")
    parser.add_argument("--version", action="version", version=f"rnhql {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    _add = sub.add_parser
    sub.add_parser = lambda *a, **k: _add(*a, formatter_class=_Help, **k)  # type: ignore

    p = sub.add_parser("scenarios", help="list built-in scenarios or validate one")
    p.add_argument("--check", metavar="FILE", help="validate a .toml or .map and print its facts")
    p.add_argument("--example", action="store_true",
                   help="print a complete scenario file, every field commented, to start from")
    add_scenario_args(p, positional=False)
    p.set_defaults(func=catalog.cmd_scenarios)

    p = sub.add_parser("train", help="train one method on one scenario",
                       epilog=_methods_epilog("rnhql train paper-50\n  rnhql train maze-1 --method "
                                              "haql --world physics --fidelity noisy"))
    add_scenario_args(p, learning=True)
    p.add_argument("--method", default="rnh-ql+",
                   help="method (default rnh-ql+: it learns the route on every built-in map, so "
                        "a first run shows learning; rnh-ql is the paper's method as published, "
                        "which fails on most maps, see the README's findings)")
    p.add_argument("--seed", type=int, default=0, help="the run's seed")
    add_training_args(p, "grid (default) or physics")
    p.add_argument("--save", metavar="AGENT.npz", help="save the trained agent")
    p.add_argument("--resume", metavar="AGENT.npz", help="continue a saved grid run")
    p.add_argument("--init", metavar="AGENT.npz",
                   help="warm start: a physics run starts from this saved agent (trained in "
                        "the grid or at a lower rung; its whole state carries over)")
    p.add_argument("--pretrain", metavar="grid:N",
                   help="a physics run first trains N episodes in the grid, then --episodes "
                        "at the rung (e.g. grid:300)")
    p.add_argument("--json", metavar="FILE", help="also write the run's record as JSON")
    add_record_args(p)
    p.set_defaults(func=train.cmd_train)

    p = sub.add_parser("route", help="print and draw a saved agent's greedy route from S")
    add_scenario_args(p, learning=True)
    p.add_argument("--agent", required=True, metavar="AGENT.npz",
                   help="an agent saved with rnhql train --save")
    add_world_args(p, "grid (default) or physics (drive it)")
    p.add_argument("--png", metavar="FILE", help="also draw the routes to a PNG")
    p.add_argument("--record", nargs="?", const=RECORD_DEFAULT, default=None,
                   metavar="PATH.rrd",
                   help="record the route to Rerun (default recordings/<scenario>-route-...)")
    p.set_defaults(func=route.cmd_route)

    p = sub.add_parser("compare", help="methods x seeds (x worlds): results, summary, figures",
                       epilog=_methods_epilog("rnhql compare paper-50 --rewards goal-only --out "
                                              "results/paper-50 --record\n  rnhql compare maze-1 "
                                              "--methods rnh-ql+,haql --world grid,physics --out "
                                              "out/"))
    add_scenario_args(p, learning=True)
    p.add_argument("--methods", help="comma-separated (default: "
                   f"{','.join(comparison_methods())})")
    p.add_argument("--seeds", type=int, default=10, help="number of seeds (default 10)")
    p.add_argument("--seed-base", type=int, default=0, help="first seed (default 0)")
    add_training_args(p, "grid, physics or grid,physics", sweep=True)
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    p.add_argument("--backend", default="local", help="local (process pool) or ray")
    p.add_argument("--address", default=None, help="Ray cluster: auto or ray://host:port")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: results.json, summary.md, figures")
    p.add_argument("--resume", action="store_true", help="skip runs already finished in DIR")
    p.add_argument("--pretrain", metavar="grid:N",
                   help="every physics run first trains N episodes in the grid (common random "
                        "numbers), then --episodes at the rung: how much robot time the grid "
                        "saves (e.g. grid:300)")
    add_record_args(p)
    p.add_argument("--record-seeds", type=int, default=1, metavar="N",
                   help="record the first N seeds of each method in full, the others as "
                        "curves only (default 1)")
    p.set_defaults(func=compare.cmd_compare)

    p = sub.add_parser("aliasing", help="next-cell distribution of every (cell, action) at a "
                                        "physics fidelity: JSON, heat map, recording")
    add_scenario_args(p)
    add_fidelity_arg(p)
    p.add_argument("--repeats", type=int, default=20, help="drives per (cell, action)")
    p.add_argument("--seed", type=int, default=0, help="noise and start-pose seed")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: aliasing.json, heat map PNG, recording")
    p.add_argument("--artifact", default=None, metavar="NAME",
                   help="also write docs/results/aliasing.NAME.json (the docs' table and "
                        "heat map)")
    p.set_defaults(func=models.cmd_aliasing)

    p = sub.add_parser("optimum", help="V*: the optimum of the physics world at a fidelity "
                                       "(expected primitives, P(G)), from a model built by "
                                       "driving")
    add_scenario_args(p)
    add_fidelity_arg(p)
    p.add_argument("--samples", type=int, default=None, metavar="K",
                   help="drives per (state, action) (default: 1 at exact, 32 above; 8 K "
                        "where they disagree)")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the model's start poses and noise streams")
    p.add_argument("--rollouts", type=int, default=0, metavar="N",
                   help="also drive the optimal policy N times from S as a check (0: no)")
    p.add_argument("--artifact", default=None, metavar="NAME",
                   help="also write docs/results/optimum.NAME.json (the table docs/fidelity.md "
                        "renders)")
    p.set_defaults(func=models.cmd_optimum)

    p = sub.add_parser("crosscheck", help="the same primitives (and policies) in IR-SIM, an "
                                          "independent simulator: how far it agrees with "
                                          "this physics at a fidelity")
    add_scenario_args(p)
    add_fidelity_arg(p)
    p.add_argument("--pairs", type=int, default=60, metavar="N",
                   help="(cell, action) pairs, a third each where the grid blocks the move, "
                        "where it is free next to an obstacle, and in the open (default 60)")
    p.add_argument("--repeats", type=int, default=4, metavar="R",
                   help="drives of each pair in each simulator above exact (default 4)")
    p.add_argument("--policy", action="append", choices=["optimal"],
                   help="also drive this policy from S in both: optimal (the grid's)")
    p.add_argument("--agent", action="append", metavar="FILE",
                   help="also drive this saved agent's greedy policy from S in both "
                        "(rnhql train --save); repeatable")
    p.add_argument("--drives", type=int, default=5, metavar="N",
                   help="drives of each policy from S in each simulator above exact "
                        "(default 5)")
    p.add_argument("--seed", type=int, default=0, help="pairs, headings and noise seed")
    p.add_argument("--json", metavar="FILE.json", help="also write the figures as JSON")
    p.add_argument("--artifact", default=None, metavar="NAME",
                   help="also write docs/results/crosscheck.NAME.json (docs/fidelity.md's "
                        "table)")
    p.set_defaults(func=models.cmd_crosscheck)
    for name in ("aliasing", "optimum", "crosscheck"):  # their artifacts name the command
        sub.choices[name].set_defaults(_parser=sub.choices[name])

    p = sub.add_parser("view", help="open a .rrd recording in the Rerun viewer")
    p.add_argument("file", metavar="FILE.rrd", help="a recording written by --record")
    p.add_argument("--web", action="store_true",
                   help="serve the web viewer on 127.0.0.1 instead of the native viewer")
    p.add_argument("--port", type=int, default=9090,
                   help="web viewer port with --web (another free one if taken; the "
                        "recording's port is always a free one)")
    p.set_defaults(func=view.cmd_view)

    p = sub.add_parser("report", help="the docs' generated tables: which are stale, and a "
                                      "refresh that re-measures them")
    p.add_argument("--refresh", action="store_true",
                   help="re-run every stale artifact's study, then regenerate the pages")
    p.add_argument("--dry-run", action="store_true",
                   help="with --refresh: print what would run and what it took last time")
    p.add_argument("--figures", action="store_true",
                   help="redraw every docs/ figure from its committed artifacts")
    p.set_defaults(func=report.cmd_report)

    p = sub.add_parser("bench", help="measure throughput")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--physics", action="store_true", help="include the physics benchmark")
    p.set_defaults(func=bench.cmd_bench)
    return parser


def _say(line: str) -> None:
    """A last line on stderr, which may be gone (a closed terminal: EIO)."""
    try:
        print(line, file=sys.stderr)
    except OSError:
        pass


WRITE_ERRNOS = {errno.ENOSPC, errno.EROFS, errno.EACCES, errno.EDQUOT, errno.EIO, errno.EFBIG}


def _in_numba_cache(err: OSError) -> bool:
    """Whether ``err`` was raised while numba saved a compiled kernel to its disk cache (its
    error names no file: without this it read as "an output file")."""
    tb = err.__traceback__
    while tb is not None:
        name = tb.tb_frame.f_code.co_filename.replace(os.sep, "/")
        if "/numba/" in name and "caching" in name:
            return True
        tb = tb.tb_next
    return False


class Terminated(KeyboardInterrupt):
    """SIGTERM (a batch scheduler, ``timeout``): the same clean-up as Ctrl-C, exit 143."""


class HungUp(Terminated):
    """SIGHUP (the terminal closed, an ssh connection dropped): the same clean-up as
    SIGTERM (finished runs kept, the recording written, the lock released), exit 129."""


_received: list[int] = []  # SIGTERM/SIGHUP seen while the command ran
QUIET_S = 5.0  # the longest a command stays silent: then a line says it still works [s]
NO_HEARTBEAT = ("view", "report")  # a viewer serves until Ctrl-C; report's studies print
#                                   to the terminal themselves, past our streams


class _Noting:
    """A text stream that notes when it was last written to (for :class:`_Heartbeat`);
    everything else is the stream's own."""

    def __init__(self, stream: object, beat: _Heartbeat) -> None:
        self._stream, self._beat = stream, beat

    def write(self, text: str) -> int:
        self._beat.last = time.monotonic()
        return self._stream.write(text)

    def __getattr__(self, name: str) -> object:
        return getattr(self._stream, name)


class _Heartbeat:
    """While a command runs, a line on stderr whenever it has printed nothing for
    :data:`QUIET_S` (a physics world compiling, V* being built, a bench measuring): a
    command that says nothing for 20 s looks hung. Progress lines and every other output
    reset the clock."""

    def __init__(self, enabled: bool = True) -> None:
        self.last = self.start = time.monotonic()
        self._stop = threading.Event()
        self._streams = sys.stdout, sys.stderr
        self._thread: threading.Thread | None = None
        if enabled:
            sys.stdout, sys.stderr = _Noting(sys.stdout, self), _Noting(sys.stderr, self)
            self._thread = threading.Thread(target=self._run, daemon=True,
                                            name="rnhql-heartbeat")
            self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.5):
            now = time.monotonic()
            if now - self.last >= QUIET_S:
                try:
                    print(f"… still working ({now - self.start:.0f} s)", file=sys.stderr,
                          flush=True)
                except (OSError, ValueError):  # the stream was closed under us: stop
                    return

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        out, err = self._streams
        if isinstance(sys.stdout, _Noting):
            sys.stdout = out
        if isinstance(sys.stderr, _Noting):
            sys.stderr = err


def _terminate(sig: int, _frame: object) -> None:
    _received.append(sig)
    raise HungUp if sig == signal.SIGHUP else Terminated


def _quiet_unraisable(unraisable: Any) -> None:
    """A SIGTERM/SIGHUP raised where Python swallows exceptions (a weakref callback, a
    ``__del__``) is in ``_received`` and acted on when the command returns: no traceback
    for it (seen while a recording was merged); anything else as Python reports it."""
    if isinstance(unraisable.exc_value, Terminated):
        return
    sys.__unraisablehook__(unraisable)


def main(argv: Sequence[str] | None = None) -> int:
    for name in ("stdout", "stderr"):  # a stream the shell closed (``>&-``): Python's None
        if getattr(sys, name) is None:
            setattr(sys, name, open(os.devnull, "w"))  # for the process's life
    parser = build_parser()
    args = parser.parse_args(argv)
    _received.clear()
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGTERM, signal.SIGHUP):
            if signal.getsignal(sig) is signal.SIG_DFL:  # SIG_IGN (nohup) stays ignored
                signal.signal(sig, _terminate)
        sys.unraisablehook = _quiet_unraisable
    beat = _Heartbeat(enabled=args.command not in NO_HEARTBEAT)
    try:
        check_empty_paths(args)
        code = int(args.func(args) or 0)
        if code == 0 and _received:
            # the signal's exception was raised where Python swallows it (a weakref
            # callback, a __del__: "Exception ignored in ..."), so the command ran on to
            # its end; what finished is kept, and the exit status still says it was stopped
            raise HungUp if _received[0] == signal.SIGHUP else Terminated
        return code
    except InputError as err:
        print(f"rnhql: error: {err}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`: not an error
        sys.stdout = open(os.devnull, "w")
        return 0
    except OSError as err:  # a full disk, a read-only file system, a file that went away
        if err.errno not in WRITE_ERRNOS:
            raise
        where = err.filename or "an output file"
        if err.strerror and str(where) in str(err.strerror):  # our own one-line messages
            print(f"rnhql: error: {err.strerror}", file=sys.stderr)
        elif err.filename is None and _in_numba_cache(err):
            cache = os.environ.get("NUMBA_CACHE_DIR") or "the packages' __pycache__ folders"
            print(f"rnhql: error: numba's kernel cache ({cache}): cannot be written "
                  f"({err.strerror}). Fix: free some space there, or point NUMBA_CACHE_DIR "
                  "at a folder with room (the compiled kernels take tens of MB)",
                  file=sys.stderr)
        else:
            print(f"rnhql: error: {where}: cannot be written ({err.strerror}). Fix: free "
                  "some space or write elsewhere", file=sys.stderr)
        return 1
    except MemoryError:  # the machine's memory, not a bug: one line (the lock is released,
        #                  the finished runs stay in runs.partial.jsonl for --resume)
        print("rnhql: error: out of memory. Fix: a smaller map or fewer --jobs, or a machine "
              "with more memory (docs/studies.md gives what runs up to 1024² take); "
              "--resume keeps the runs already finished", file=sys.stderr)
        return 1
    except Exception as err:
        if isinstance(err, CheckpointError):
            print(f"rnhql: error: {err}", file=sys.stderr)
            return 2
        if isinstance(err, LearnerError):  # the user's own learner failed: the run did
            print(f"rnhql: the run failed: {err}", file=sys.stderr)
            return 1
        if isinstance(err, SweepError):
            print(f"rnhql: {err}", file=sys.stderr)
            return 1
        raise
    except HungUp:
        _say("rnhql: hung up (SIGHUP)")
        return 129
    except Terminated:
        _say("rnhql: terminated")
        return 143
    except KeyboardInterrupt:
        print("rnhql: interrupted", file=sys.stderr)
        return 130
    finally:
        beat.stop()


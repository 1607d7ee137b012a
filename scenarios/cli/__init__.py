"""The ``rnhql`` command: the parser (:mod:`~scenarios.cli.app`) and one module per subcommand.

The top of the stack: may import every other part of ``scenarios``, nothing imports it.
:func:`main` imports the parser lazily so that a Ctrl-C while the heavy modules load
(numpy, numba, pymunk: about half a second) is one line and exit 130 like any other,
and a Ctrl-C after the command has finished (interpreter shutdown) is ignored: the
work is done and its exit status stands; a SIGTERM or SIGHUP there ends the process at
once with that status (it was a traceback from a garbage collector's callback, or a
status killed by the signal). SIGTERM and SIGHUP while the modules load end the command
with one line and 143 or 129, as they do later.
"""

from __future__ import annotations

import functools
import os
import signal
import sys
import threading
from collections.abc import Sequence


class _StoppedWhileStarting(Exception):
    """SIGTERM or SIGHUP while the heavy modules loaded: nothing had started."""

    def __init__(self, sig: int) -> None:
        super().__init__(sig)
        self.sig = sig


def main(argv: Sequence[str] | None = None) -> int:
    from scenarios.memory_limit import prepare

    too_small = prepare()  # before numpy loads (its BLAS threads)
    if too_small is not None:
        print(too_small, file=sys.stderr)
        return 1
    try:
        run = _import_app()
        code = run(argv)
    except _StoppedWhileStarting as stop:
        hup = stop.sig == signal.SIGHUP
        try:
            print(f"rnhql: {'hung up (SIGHUP)' if hup else 'terminated'}", file=sys.stderr)
        except OSError:  # the terminal is gone
            pass
        code = 129 if hup else 143
    except KeyboardInterrupt:
        print("rnhql: interrupted", file=sys.stderr)
        code = 130
    except ImportError as err:  # a Ctrl-C inside a C extension's import surfaces as this
        cause: BaseException | None = err
        while cause is not None and not isinstance(cause, KeyboardInterrupt):
            cause = cause.__cause__ or cause.__context__
        if cause is None:
            raise
        print("rnhql: interrupted", file=sys.stderr)
        code = 130
    if argv is None and code == 130:
        # the console script, interrupted (its handlers have kept what finished): exit now
        # with 130. Left to the interpreter's shutdown, an interrupt that once hit the
        # import machinery or compiled code can still end the process as killed by SIGINT.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    if argv is None:  # the console script: nothing after this may turn into a traceback
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        for sig in (signal.SIGTERM, signal.SIGHUP):  # nor a status killed by a signal
            if signal.getsignal(sig) is not signal.SIG_IGN:
                signal.signal(sig, functools.partial(_exit_now, code))
    return code


def _exit_now(code: int, _sig: int, _frame: object) -> None:
    """SIGTERM or SIGHUP once the command has finished: end now, with its exit status."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code)


def _import_app():
    """The parser's module, imported with Ctrl-C held until the imports are done: a
    KeyboardInterrupt raised inside a library's optional import can surface as an
    ImportError that the library catches and ignores, and the command then ran on as if
    never interrupted (seen once in CI: exit 0). A Ctrl-C pressed meanwhile is raised
    right after, as one."""
    pressed: list[int] = []
    held = {}
    if threading.current_thread() is threading.main_thread():  # signals are the main thread's
        held[signal.SIGINT] = signal.signal(signal.SIGINT, lambda s, _f: pressed.append(s))
        for sig in (signal.SIGTERM, signal.SIGHUP):  # likewise (unless ignored: nohup)
            if signal.getsignal(sig) is signal.SIG_DFL:
                held[sig] = signal.signal(sig, lambda s, _f: pressed.append(s))
    try:
        # lazy by design: main() imports the parser itself (the package docstring says why)
        from scenarios.cli.app import main as run
    finally:
        for sig, old in held.items():
            signal.signal(sig, old)
    if signal.SIGINT in pressed:
        raise KeyboardInterrupt
    if pressed:
        raise _StoppedWhileStarting(pressed[0])
    return run


__all__ = ["main"]

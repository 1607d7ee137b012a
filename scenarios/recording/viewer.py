"""Serve one recording to a browser with Rerun's web viewer, as a child that never outlives us.

``rerun FILE --serve-web`` runs two servers: an HTTP server for the viewer's page and
a gRPC proxy that holds the recording. The page shows the recording only when its
address names the proxy (``http://HOST:WEB/?url=rerun%2Bhttp%3A%2F%2FHOST%3AGRPC%2Fproxy``);
the bare ``http://HOST:WEB`` opens Rerun's welcome page. Rerun prints that address only
inside a log line and defaults both ports to fixed numbers (9090, 9876), so a second
viewer fails to start. :class:`WebViewer` therefore

* picks a free port for each server (a requested web port is used when it is free),
  and retries with fresh ports if another process took one between the pick and
  Rerun's bind;
* prints nothing itself: it hands back the one address (:attr:`WebViewer.url`) once
  both servers answer, and :func:`ssh_hint` names both ports for forwarding;
* starts the ``rerun`` binary in its own process group (the ``rerun`` script of
  rerun-sdk is a Python wrapper that runs the binary as *its* child, so stopping the
  wrapper alone left the viewer running) and stops the whole group on
  :meth:`WebViewer.stop`, which :func:`stopping_on_signals` turns SIGTERM and SIGHUP
  into (SIGINT already raises ``KeyboardInterrupt``). On Linux the child is also told
  to exit if we die without cleaning up (SIGKILL): ``PR_SET_PDEATHSIG``.
"""

from __future__ import annotations

import collections
import contextlib
import ctypes
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterator
from pathlib import Path

HOST = "127.0.0.1"  # loopback only: a recording is not published to the network
START_TIMEOUT_S = 60.0  # a busy 2-core machine takes a few seconds to start Rerun
STOP_TIMEOUT_S = 5.0  # SIGTERM, then SIGKILL after this long
ATTEMPTS = 3  # fresh ports after a lost race for a port


class ViewerError(RuntimeError):
    """The web viewer did not start; the message ends with what Rerun said."""


class Stopped(KeyboardInterrupt):
    """SIGTERM or SIGHUP while serving: clean up like Ctrl-C, exit 128 + signal."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def rerun_cli() -> str:
    """The ``rerun`` command of this environment."""
    local = Path(sys.executable).with_name("rerun")
    return str(local) if local.exists() else (shutil.which("rerun") or "rerun")


def rerun_binary() -> str:
    """The ``rerun`` executable itself (rerun-sdk ships it inside ``rerun_cli``), so the
    process we stop is the viewer and not a wrapper around it; else the ``rerun`` command."""
    try:
        # optional: rerun-sdk may ship no rerun_cli package (then the `rerun` command)
        import rerun_cli as package
    except ImportError:
        return rerun_cli()
    exe = Path(package.__file__).with_name("rerun.exe" if sys.platform == "win32" else "rerun")
    return str(exe) if exe.is_file() and os.access(exe, os.X_OK) else rerun_cli()


def free_port(host: str = HOST) -> int:
    """A TCP port nobody listens on now (the kernel's pick, so two callers differ)."""
    with socket.socket() as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def port_is_free(port: int, host: str = HOST) -> bool:
    with socket.socket() as s:
        try:
            s.bind((host, port))
        except OSError:
            return False
        return True


def viewer_url(web_port: int, grpc_port: int, host: str = HOST) -> str:
    """The address that opens the recording: the page, told where the proxy is."""
    source = urllib.parse.quote(f"rerun+http://{host}:{grpc_port}/proxy", safe="")
    return f"http://{host}:{web_port}/?url={source}"


def ssh_hint(web_port: int, grpc_port: int) -> str:
    """The command that forwards both servers from a remote machine: the page loads from
    one port and then fetches the recording from the other."""
    return (f"ssh -L {web_port}:{HOST}:{web_port} -L {grpc_port}:{HOST}:{grpc_port} "
            "USER@HOST")


def _die_with_parent() -> None:  # pragma: no cover - runs in the child between fork and exec
    """Linux: SIGTERM this child when the process that started it dies (even by SIGKILL)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def spawn(args: list[str], output: int | None = None) -> subprocess.Popen[str]:
    """``rerun ARGS`` in a process group of its own (stopped with :func:`stop_group`), told
    to exit with us on Linux; Rerun logs warnings and errors only (its INFO lines carry a
    second, different address). ``output``: where its stdout and stderr go (None: ours)."""
    env = {**os.environ, "RUST_LOG": os.environ.get("RNHQL_RERUN_LOG", "warn")}
    return subprocess.Popen(
        [rerun_binary(), *args], stdin=subprocess.DEVNULL, stdout=output,
        stderr=None if output is None else subprocess.STDOUT, text=True, errors="replace",
        env=env, start_new_session=True,
        preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None)


def stop_group(proc: subprocess.Popen[str]) -> None:
    """SIGTERM the child's process group, SIGKILL it after ``STOP_TIMEOUT_S``; and SIGKILL
    what is left of the group (a wrapper's child) once the child is gone."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(timeout=STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)


class WebViewer:
    """``rerun FILE --serve-web`` on two free loopback ports; use as a context manager."""

    def __init__(self, path: str | Path, web_port: int | None = None) -> None:
        self.path = Path(path)
        self.requested_port = web_port
        self.web_port = self.grpc_port = 0
        self.proc: subprocess.Popen[str] | None = None
        self._lines: collections.deque[str] = collections.deque(maxlen=40)
        self._ready = threading.Event()

    @property
    def url(self) -> str:
        return viewer_url(self.web_port, self.grpc_port)

    @property
    def web_port_moved(self) -> bool:
        """The requested web port was taken, so another one is used."""
        return self.requested_port is not None and self.web_port != self.requested_port

    # ---------------------------------------------------------------- starting
    def start(self) -> WebViewer:
        """Start Rerun and return once both servers answer (raises :class:`ViewerError`)."""
        for attempt in range(ATTEMPTS):
            want = self.requested_port if attempt == 0 else None
            self.web_port = want if want and port_is_free(want) else free_port()
            self.grpc_port = free_port()
            while self.grpc_port == self.web_port:
                self.grpc_port = free_port()
            self._spawn()
            if self._wait_until_serving():
                self._ready.set()  # from now on Rerun's warnings go to our stderr
                return self
            self.stop()
        said = "\n".join(self._lines).strip() or "(nothing)"
        raise ViewerError(f"the Rerun web viewer did not start ({ATTEMPTS} tries); "
                          f"Rerun said:\n{said}")

    def _spawn(self) -> None:
        self._lines.clear()
        self.proc = spawn([str(self.path), "--serve-web", "--bind", HOST, "--web-viewer-port",
                           str(self.web_port), "--port", str(self.grpc_port)],
                          output=subprocess.PIPE)
        threading.Thread(target=self._pump, args=(self.proc,), daemon=True,
                         name="rnhql-rerun-output").start()

    def _pump(self, proc: subprocess.Popen[str]) -> None:
        """Keep Rerun's output (for an error message); pass it on once serving."""
        assert proc.stdout is not None
        for line in proc.stdout:
            self._lines.append(line.rstrip())
            if self._ready.is_set():
                with contextlib.suppress(OSError, ValueError):
                    sys.stderr.write(line)

    def _answers(self) -> bool:
        try:
            with urllib.request.urlopen(f"http://{HOST}:{self.web_port}/", timeout=2) as r:
                if r.status != 200:
                    return False
            with socket.create_connection((HOST, self.grpc_port), timeout=2):
                return True
        except (OSError, urllib.error.URLError):
            return False

    def _wait_until_serving(self) -> bool:
        """True once both ports answer while our child is alive (another process that
        happened to take a port would answer too, but our child would have exited)."""
        assert self.proc is not None
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                return False
            if self._answers():
                return self.proc.poll() is None
            time.sleep(0.2)
        return False

    # ---------------------------------------------------------------- running, stopping
    def wait(self) -> int:
        assert self.proc is not None
        return self.proc.wait()

    def stop(self) -> None:
        """Stop Rerun's whole process group. Safe to call twice."""
        proc, self.proc = self.proc, None
        if proc is not None:
            stop_group(proc)

    def __enter__(self) -> WebViewer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _raise_stopped(signum: int, _frame: object) -> None:
    raise Stopped(signum)


@contextlib.contextmanager
def stopping_on_signals() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`Stopped` in the block (so ``finally`` clauses stop
    the children); old handlers come back after. Main thread only, like all handlers."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    sigs = [s for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None))
            if s is not None]
    old = {s: signal.signal(s, _raise_stopped) for s in sigs}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)

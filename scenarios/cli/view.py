"""``rnhql view``: open a recording in the native or the web Rerun viewer.

With ``--web`` the output is what a user on a headless or remote machine needs and
nothing else: the one address that opens the recording, and the ssh command that
forwards both of the viewer's ports. The viewer (:mod:`scenarios.recording.viewer`)
runs on free ports, so several views can run at once, and it stops with us on
Ctrl-C, SIGTERM or SIGHUP.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from scenarios.recording.viewer import (
    Stopped,
    ViewerError,
    WebViewer,
    spawn,
    ssh_hint,
    stop_group,
    stopping_on_signals,
)
from sim.errors import InputError

RRD_MAGIC = b"RRF"  # every .rrd starts "RRF" and a format digit ("RRF2" for rerun 0.41)


def _check_display(path: Path) -> None:
    if sys.platform.startswith("linux") and not (
            os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise InputError(str(path), "--web", "no display for the native viewer (neither "
                         "DISPLAY nor WAYLAND_DISPLAY is set)",
                         f"serve it to a browser instead: rnhql view {path} --web "
                         "(then open the one address it prints)")


def _serve_web(path: Path, port: int | None) -> int:
    viewer = WebViewer(path, web_port=port or None)
    try:  # stopped however we leave, a signal during the start included
        try:
            viewer.start()
        except ViewerError as err:
            print(f"rnhql: error: {path}: {err}", file=sys.stderr)
            return 1
        moved = (f" (port {port} is busy, so {viewer.web_port})" if viewer.web_port_moved
                 else "")
        print(f"serving {path}{moved}; open this address in a browser:\n\n"
              f"    {viewer.url}\n\n"
              f"on another machine, forward both ports first (the page is on "
              f"{viewer.web_port}, the recording on {viewer.grpc_port}):\n"
              f"    {ssh_hint(viewer.web_port, viewer.grpc_port)}\n"
              "Ctrl-C stops the viewer.", flush=True)
        return viewer.wait()
    finally:
        viewer.stop()


def _open_native(path: Path) -> int:
    # lazy: scenarios.recording.viewer costs 9 ms at startup (and tests/test_security.py
    # stands in for viewer.spawn: looked up per call)
    proc = spawn([str(path)])
    try:
        return proc.wait()
    finally:
        stop_group(proc)


def cmd_view(args: argparse.Namespace) -> int:
    """Open a recording: the native viewer, or the web viewer served on loopback."""
    path = Path(args.file)
    if not path.exists():
        raise InputError(str(path), "FILE", "does not exist", "pass a .rrd written by --record")
    if not path.is_file():
        raise InputError(str(path), "FILE", "is not a regular file (a folder, device or FIFO)",
                         "pass a .rrd written by --record")
    if path.stat().st_size == 0:
        raise InputError(str(path), "FILE", "is empty (a recording stopped before it wrote "
                         "anything)", "record the run again")
    with path.open("rb") as f:
        magic = f.read(3)
    if magic != RRD_MAGIC:
        raise InputError(str(path), "FILE", "is not a Rerun recording (it does not start as "
                         "an .rrd does)", "pass a .rrd written by --record")
    if args.port is not None and not 1 <= args.port <= 65535:
        raise InputError("command line", "--port", f"{args.port} is not a port",
                         "pass a port in 1..65535, e.g. --port 9090")
    # absolute: a file named like a flag ("--version") must reach rerun as a path, not a flag
    path = path.absolute()
    if not args.web:
        _check_display(path)
    try:
        with stopping_on_signals():
            return _serve_web(path, args.port) if args.web else _open_native(path)
    except Stopped as stop:  # SIGTERM, SIGHUP: the viewer is stopped (finally above)
        print(f"rnhql: viewer stopped ({stop})", file=sys.stderr)
        return 128 + stop.signum
    except KeyboardInterrupt:  # Ctrl-C is how a viewer is closed: not an error
        return 0

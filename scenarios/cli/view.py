"""``rnhql view``: open a recording in the native or the web Rerun viewer.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from sim.errors import InputError


def cmd_view(args: argparse.Namespace) -> int:
    """Open a recording: the native viewer, or the web viewer served on loopback."""
    import subprocess

    from scenarios.recording.recorder import rerun_cli

    path = Path(args.file)
    if not path.is_file():
        raise InputError(str(path), "FILE", "does not exist", "pass a .rrd written by --record")
    import os
    import sys

    cmd = [rerun_cli(), str(path)]
    if not args.web and sys.platform.startswith("linux") and not (
            os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise InputError(str(path), "--web", "no display for the native viewer (neither "
                         "DISPLAY nor WAYLAND_DISPLAY is set)",
                         f"serve it to a browser instead: rnhql view {path} --web "
                         "(then open the printed address; ssh -L the port if remote)")
    if args.web:
        cmd += ["--serve-web", "--bind", "127.0.0.1", "--web-viewer-port", str(args.port)]
        print(f"serving {path} at http://127.0.0.1:{args.port} (Ctrl-C to stop)")
    try:
        return subprocess.call(cmd)
    except KeyboardInterrupt:
        return 0

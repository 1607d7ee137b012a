"""``rnhql view --web``: the one address, free ports, both named for ssh, no child left behind.

These start the real ``rerun`` web viewer (about a second each) as ``rnhql view`` would
be started by a user, in a process of its own, and read what it prints.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.parse
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from scenarios.recording.viewer import ssh_hint, viewer_url

REPO = Path(__file__).resolve().parent.parent
URL = re.compile(r"^\s+(http://127\.0\.0\.1:(\d+)/\?url=\S+)$", re.M)

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="reads /proc to find the viewer's processes")


@pytest.fixture(scope="module")
def rrd(tmp_path_factory, paper50, paper50_model):
    from scenarios.recording.demo import record_synthetic

    path = tmp_path_factory.mktemp("view") / "run.rrd"
    record_synthetic(path, paper50, paper50_model, episodes=10, record_every=5, values_every=5)
    return path


def default_signals() -> None:
    """The child starts with the default SIGINT and SIGHUP, whatever this test run inherited
    (a background job or ``nohup`` ignores them, and an ignored signal stays ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)


@contextlib.contextmanager
def viewing(rrd: Path, *extra: str) -> Iterator[tuple[subprocess.Popen, str]]:
    """``rnhql view RRD --web`` in a process group of its own: (process, what it printed up
    to its last line). Afterwards the group is SIGKILLed if it still runs."""
    proc = subprocess.Popen([sys.executable, "-m", "scenarios.cli", "view", str(rrd), "--web",
                             *extra], cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True,
                            preexec_fn=default_signals)
    try:
        out = []
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            out.append(line)
            if line.startswith("Ctrl-C stops"):
                break
        assert out and out[-1].startswith("Ctrl-C stops"), "no address:\n" + "".join(out)
        yield proc, "".join(out)
    finally:
        if proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)
        proc.stdout.close()


def stop(proc: subprocess.Popen, sig: int = signal.SIGTERM) -> int:
    proc.send_signal(sig)
    return proc.wait(timeout=30)


def ports_of(text: str) -> tuple[int, int]:
    """(web port, gRPC port) of the printed address."""
    m = URL.search(text)
    assert m, text
    query = urllib.parse.parse_qs(urllib.parse.urlsplit(m.group(1)).query)
    proxy = urllib.parse.urlsplit(query["url"][0])
    assert (proxy.scheme, proxy.hostname, proxy.path) == ("rerun+http", "127.0.0.1", "/proxy")
    return int(m.group(2)), int(proxy.port)


def descendants(pid: int) -> set[int]:
    """Every live process below ``pid`` (from /proc)."""
    children: dict[int, list[int]] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            children.setdefault(ppid, []).append(int(d.name))
    out, todo = set(), [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.add(c)
            todo.append(c)
    return out


def alive(pid: int) -> bool:
    """Running (a zombie waiting for its new parent to reap it is not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def listening(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(1)
        return s.connect_ex(("127.0.0.1", port)) == 0


def test_address_names_the_proxy_url_encoded():
    assert viewer_url(9090, 9876) == (
        "http://127.0.0.1:9090/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A9876%2Fproxy")
    assert ssh_hint(1, 2) == "ssh -L 1:127.0.0.1:1 -L 2:127.0.0.1:2 USER@HOST"


def test_two_views_at_once_get_distinct_ports_both_named(rrd):
    with viewing(rrd) as (a, out_a), viewing(rrd) as (b, out_b):  # the same default --port
        ports = [*ports_of(out_a), *ports_of(out_b)]
        assert len(set(ports)) == 4, (out_a, out_b)
        for out in (out_a, out_b):
            web, grpc = ports_of(out)
            assert f"-L {web}:127.0.0.1:{web} -L {grpc}:127.0.0.1:{grpc}" in out
            assert out.count("http://") == 1  # one address, and only the one that works
            with urllib.request.urlopen(f"http://127.0.0.1:{web}/", timeout=10) as r:
                assert r.status == 200 and b"<html" in r.read().lower()
            assert listening(grpc)
        assert stop(b) == 143 and stop(a) == 143


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 0),
                                           (signal.SIGHUP, 129)])
def test_a_signal_stops_the_rerun_child(rrd, sig, code):
    with viewing(rrd) as (proc, out):
        web, grpc = ports_of(out)
        kids = descendants(proc.pid)
        assert kids, "the viewer runs as a child of rnhql view"
        assert stop(proc, sig) == code
    deadline = time.monotonic() + 10
    while any(alive(k) for k in kids) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [k for k in kids if alive(k)], f"rerun survived {sig.name}"
    assert not listening(web) and not listening(grpc)


def test_a_taken_port_is_reported_and_another_used(rrd):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        taken = s.getsockname()[1]
        with viewing(rrd, "--port", str(taken)) as (_proc, out):
            web, _ = ports_of(out)
            assert web != taken and f"port {taken} is busy" in out


@pytest.mark.slow
def test_the_printed_address_opens_the_recording_in_a_browser(rrd, tmp_path):
    """A real browser (Chromium via Playwright): the printed address shows the recording's
    map, the bare page does not (Rerun's welcome page). Drawn with the software
    rasteriser: about a minute on two cores."""
    pytest.importorskip("playwright")
    import numpy as np
    from playwright.sync_api import sync_playwright

    from scenarios.recording.scene import OBSTACLE, TRAIN

    chromium = "/usr/bin/chromium"
    if not os.path.exists(chromium):
        pytest.skip("no Chromium")
    with viewing(rrd) as (proc, out):
        url = URL.search(out).group(1)
        web, _ = ports_of(out)
        shots = {}
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=chromium, args=[
                "--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader"])
            # headless Chromium has no working WebGPU: ask Rerun for WebGL, as a user's
            # browser without WebGPU gets anyway
            for name, address in (("printed", url + "&renderer=webgl"),
                                  ("bare", f"http://127.0.0.1:{web}/?renderer=webgl")):
                page = browser.new_page(viewport={"width": 1400, "height": 900})
                page.goto(address)
                page.wait_for_timeout(40_000)
                shots[name] = tmp_path / f"{name}.png"
                page.screenshot(path=str(shots[name]))
                page.close()
            browser.close()
        stop(proc)
    from matplotlib.image import imread

    def pixels_like(png: Path, rgb: tuple[int, int, int]) -> int:
        img = (imread(png)[..., :3] * 255).astype(int)
        return int((np.abs(img - np.array(rgb)).max(axis=2) <= 10).sum())

    # the map's obstacle discs and training trajectory (about 34 000 and 1 700 pixels when
    # drawn; the welcome page's grey text and orange warning make a few hundred and a few)
    for colour, least in ((OBSTACLE, 10_000), (TRAIN, 500)):
        printed, bare = pixels_like(shots["printed"], colour), pixels_like(shots["bare"], colour)
        assert printed > least and bare < least / 5, (colour, printed, bare)


@pytest.mark.parametrize(("make", "argv_tail", "says"), [
    (lambda p: p.write_bytes(b""), [], "is empty"),
    (lambda p: p.mkdir(), [], "is not a regular file"),
    (lambda p: p.write_bytes(b"RRF2"), ["--web", "--port", "65536"], "65536 is not a port"),
    (lambda p: p.write_bytes(b"RRF2"), ["--web", "--port", "-1"], "-1 is not a port"),
    (lambda p: p.write_text("not a recording"), ["--web"], "is not a Rerun recording"),
])
def test_view_refuses_bad_input_in_one_line(tmp_path, capsys, make, argv_tail, says):
    from scenarios.cli import main

    path = tmp_path / "x.rrd"
    make(path)
    assert main(["view", str(path), *argv_tail]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err

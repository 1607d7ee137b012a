"""A seeded generator of hostile inputs for the ``rnhql`` command, and a tally of how it ends.

Why: the unit tests pin the cases someone thought of; this draws new ones of the same
kinds (mutated scenario TOML, ``.map`` and ``.scen`` files, tampered checkpoints, damaged
resume state, outputs aimed at devices, FIFOs, symlinks, hard links and folders,
unchecked numbers, full disks, signals, learner modules of the user's that misbehave, env
options and actions a cast would change, runs edited behind ``--resume``, a lock naming a
stranger's pid, address-space limits) from a seed, runs each as a real process, and sorts
the outcome:

- clean: the expected result (a valid run, or one ``rnhql: error: ... Fix: ...`` line with
  the expected exit status) and nothing lost or replaced;
- traceback, hang (no exit within the timeout), crash (killed by a signal, or a status the
  CLI never uses), silent (exit 0 on nonsense, or an output that replaced a device, or a
  NaN in the output), wrong exit (a status or message other than the expected one).

Run: ``python tests/hostile_probe.py --seed 1 --cases 120`` from the repository root; add
``--show`` to print every case that is not clean. Not collected by pytest (no ``test_``
prefix): it takes minutes.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import functools
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PY = sys.executable
BASE_TOML = (REPO / "sim/builtin/paper-50.toml").read_text()
SMALL_MAP = "type octile\nheight 8\nwidth 8\nmap\n" + "\n".join(
    ["........", ".@@@....", "........", "....@@..", "........", "..@.....", "........",
     "........"]) + "\n"
TRAIN = ["--method", "st-ql", "--episodes", "5"]


@dataclass
class Case:
    kind: str
    argv: list[str]
    expect: str  # "ok", "error2", "error1", "ok|error2", "ok|error1", "signal"
    setup: Callable[[Path], None] = lambda d: None
    check: Callable[[Path], str | None] = lambda d: None  # a problem after the run, or None
    send: tuple[int, float] | None = None  # (signal, seconds after start)
    env: dict[str, str] = field(default_factory=dict)
    note: str = ""
    python: str | None = None  # run this snippet (python -c) instead of the command
    limit_bytes: int | None = None  # an address-space limit (ulimit -v) for the process


def _write(name: str, data: bytes | str) -> Callable[[Path], None]:
    def setup(d: Path) -> None:
        (d / name).write_bytes(data.encode() if isinstance(data, str) else data)
    return setup


# ---------------------------------------------------------------- scenario TOML
HOSTILE_NUMBERS = ["inf", "nan", "-1", "0", "1e308", "-1e308", "10" + "0" * 45, "1e-9",
                   "123456789012345678901234567890", "-0.0", "4e9", "true", '"x"', "[]"]


def toml_case(rng: random.Random) -> Case:
    text = BASE_TOML
    lines = text.splitlines()
    kind = rng.choice(["number", "number", "nest", "drop", "unknown", "bytes", "truncate",
                       "chain", "map-dev", "seed", "circle", "steps-phys", "name"])
    expect = "ok|error2"
    argv_extra: list[str] = []
    if kind == "number":
        idx = [i for i, ln in enumerate(lines) if "=" in ln and not ln.startswith(("name",
                                                                                "description"))]
        i = rng.choice(idx)
        key = lines[i].split("=")[0]
        lines[i] = f"{key}= {rng.choice(HOSTILE_NUMBERS)}"
        text = "\n".join(lines)
    elif kind == "nest":
        depth = rng.choice([500, 3000, 20000])
        text = "x = " + "[" * depth + "]" * depth + "\n" if rng.random() < 0.5 else \
            "x = " + "{a = " * depth + "1" + "}" * depth + "\n"
        expect = "error2"
    elif kind == "drop":
        del lines[rng.randrange(len(lines))]
        text = "\n".join(lines)
    elif kind == "unknown":
        lines.insert(rng.randrange(1, len(lines)), f"bogus_{rng.randrange(99)} = 1")
        text = "\n".join(lines)
        expect = "ok|error2"
    elif kind == "bytes":
        raw = bytearray(text.encode())
        for _ in range(rng.randrange(1, 5)):
            raw[rng.randrange(len(raw))] = rng.randrange(256)
        text = bytes(raw)  # type: ignore[assignment]
    elif kind == "truncate":
        text = text[: rng.randrange(len(text))]
    elif kind == "chain":
        spacing = rng.choice(["1e-9", "1e-6", "0.0001", "1e-300"])
        text += f"\n[[obstacles.chains]]\nfrom = [0.0, 0.0]\nto = [50.0, 50.0]\n" \
                f"radius_m = 0.5\nspacing_m = {spacing}\n"
        expect = "error2"
    elif kind == "map-dev":
        target = rng.choice(["/dev/zero", "/dev/urandom", "fifo.map"])
        text = "\n".join(ln for ln in lines if not ln.startswith(("width_m", "height_m"))
                         and "obstacles" not in ln and not ln.startswith(
                             ("count", "radius_m", "seed"))) + '\n'
        text = text.replace("[arena]", f'[arena]\nmap = "{target}"')
        expect = "error2"
    elif kind == "seed":
        text = text.replace("seed = 50", f"seed = {rng.choice(['-1', '-99', str(2**70)])}")
        expect = "error2"
    elif kind == "circle":
        text = text.replace("[obstacles.random]", "[obstacles]\ncircles = [[" + rng.choice(
            ["1e308, 1e308, 1.0", "10.0, 10.0, 1e308", "-1e308, 5.0, 2.0",
             "1e200, 1e200, 1e200"]) + "]]\n[obstacles.random]")
        expect = "ok|error2"
    elif kind == "steps-phys":
        text = text.replace("steps_per_episode = 600",
                            f"steps_per_episode = {rng.choice([10_000_000, 5_000_000])}")
        argv_extra = ["--world", "physics", "--episodes", "1"]
        expect = "error2"
    elif kind == "name":
        text = text.replace('name = "paper-50"', f'name = "{"n" * rng.choice([300, 5000])}"')
        argv_extra = ["--record"]
        expect = "ok"

    def setup(d: Path, text=text) -> None:
        (d / "s.toml").write_bytes(text if isinstance(text, bytes) else text.encode())
        os.mkfifo(d / "fifo.map")

    argv = ["train", "s.toml", *TRAIN, *argv_extra]
    if argv_extra[:2] == ["--world", "physics"]:
        argv = ["train", "s.toml", "--method", "st-ql", *argv_extra]
    return Case(f"toml:{kind}", argv, expect, setup)


# ---------------------------------------------------------------- .map and .scen
def map_case(rng: random.Random) -> Case:
    kind = rng.choice(["header", "huge", "char", "bytes", "rows", "empty", "fifo", "dir"])
    text: str | bytes = SMALL_MAP
    expect = "error2"
    if kind == "header":
        text = SMALL_MAP.replace("height 8", rng.choice(["height -3", "height x", "height 0",
                                                         "height 8 8", "heigth 8"]))
    elif kind == "huge":
        n = rng.choice([10**8, 10**12, 5000, 4097])
        text = f"type octile\nheight {n}\nwidth {n}\nmap\n" + "." * 10 + "\n"
    elif kind == "char":
        raw = list(SMALL_MAP)
        raw[rng.randrange(40, len(raw) - 1)] = rng.choice(["#", "\t", "é", "\x00", "?"])
        text = "".join(raw)
    elif kind == "bytes":
        text = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300)))
    elif kind == "rows":
        text = SMALL_MAP + "........\n" * rng.randrange(1, 4)
    elif kind == "empty":
        text = ""
    argv = ["train", "m.map", "--start", "0,0", "--goal", "7,7", *TRAIN]

    def setup(d: Path) -> None:
        if kind == "fifo":
            os.mkfifo(d / "m.map")
        elif kind == "dir":
            (d / "m.map").mkdir()
        else:
            (d / "m.map").write_bytes(text if isinstance(text, bytes) else text.encode())
    return Case(f"map:{kind}", argv, expect, setup)


def scen_case(rng: random.Random) -> Case:
    kind = rng.choice(["negative", "escape", "columns", "bytes", "index", "fifo", "size",
                       "number"])
    good = "version 1\n0\tm.map\t8\t8\t0\t0\t7\t7\t9.9\n"
    text: str | bytes = good
    index = "0"
    expect = "error2"
    if kind == "negative":
        text = good.replace("\t0\t0\t", "\t-5\t0\t")
    elif kind == "escape":
        text = good.replace("m.map", rng.choice(["../m.map", "/etc/passwd", "/dev/zero",
                                                 "fifo.map"]))
    elif kind == "columns":
        text = good.replace("\t9.9", "")
    elif kind == "bytes":
        text = b"version 1\n" + bytes(rng.randrange(256) for _ in range(80))
    elif kind == "index":
        index = rng.choice(["-1", "99", str(2**63)])
    elif kind == "size":
        text = good.replace("\t8\t8\t", "\t99999999999\t8\t")
    elif kind == "number":
        text = good.replace("9.9", rng.choice(["nan", "inf", "1e400", "x"]))
        expect = "ok|error2"

    def setup(d: Path) -> None:
        (d / "m.map").write_text(SMALL_MAP)
        os.mkfifo(d / "fifo.map")
        if kind == "fifo":
            os.mkfifo(d / "p.scen")
        else:
            (d / "p.scen").write_bytes(text if isinstance(text, bytes) else text.encode())
    return Case(f"scen:{kind}", ["train", "--scen", "p.scen", "--index", index, *TRAIN],
                expect, setup)


# ---------------------------------------------------------------- checkpoints
_CKPT: dict[str, bytes] = {}


def _base_checkpoint(method: str) -> bytes:
    if method not in _CKPT:
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run([PY, "-m", "scenarios.cli", "train", "paper-50", "--method", method,
                            "--episodes", "20", "--save", f"{tmp}/a.npz"], cwd=REPO,
                           capture_output=True, check=True, env=_env({}))
            _CKPT[method] = Path(f"{tmp}/a.npz").read_bytes()
    return _CKPT[method]


def _rewrite_npz(data: bytes, edit: Callable[[dict], None]) -> bytes:
    import io

    import numpy as np

    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    edit(arrays)
    out = io.BytesIO()
    np.savez(out, **arrays)
    return out.getvalue()


def _claim_shape(data: bytes, member: str, shape: tuple[int, ...]) -> bytes:
    """The same file with ``member``'s .npy header claiming ``shape`` (the data unchanged)."""
    import io

    src = zipfile.ZipFile(io.BytesIO(data))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as dst:
        for info in src.infolist():
            raw = src.read(info.filename)
            if info.filename == member + ".npy":
                head_len = int.from_bytes(raw[8:10], "little")
                header = raw[10:10 + head_len].decode("latin1")
                start = header.index("'shape': (") + len("'shape': (")
                end = header.index(")", start)
                dims = ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "")
                new = header[:start] + dims + header[end:]
                new = new.rstrip() + " " * max(0, head_len - len(new.rstrip()) - 1) + "\n"
                raw = raw[:8] + len(new).to_bytes(2, "little") + new.encode("latin1") + \
                    raw[10 + head_len:]
            dst.writestr(info, raw)
    return out.getvalue()


def checkpoint_case(rng: random.Random) -> Case:
    import json

    import numpy as np

    method = rng.choice(["st-ql", "rnh-ql"])
    kind = rng.choice(["huge-header", "inf", "big", "nan", "drop-metric", "other-scenario",
                       "truncate", "k", "config-json", "fifo", "dir"])
    base = _base_checkpoint(method)
    data = base
    expect = "error2"
    cmd = rng.choice(["resume", "route"])
    scenario = "paper-50"
    if kind == "huge-header":
        data = _claim_shape(base, "state_q", (10**12, 4))
    elif kind in ("inf", "big", "nan"):
        value = {"inf": rng.choice([np.inf, -np.inf]), "big": rng.choice([1e308, -1e300]),
                 "nan": np.nan}[kind]

        def edit(a: dict) -> None:
            q = a["state_q"].copy()
            q[rng.randrange(q.shape[0]), rng.randrange(4)] = value
            a["state_q"] = q
        data = _rewrite_npz(base, edit)
    elif kind == "drop-metric":
        name = rng.choice(["metric_success", "metric_steps", "metric_returns"])
        data = _rewrite_npz(base, lambda a: a.pop(name))
        cmd = "resume"
    elif kind == "other-scenario":
        scenario = "zigzag-50"
        cmd = "route"
    elif kind == "truncate":
        data = base[: rng.randrange(len(base))]
    elif kind == "k":
        method = "rnh-ql"
        base = _base_checkpoint(method)

        def edit(a: dict) -> None:
            cfg = json.loads(str(a["config"]))
            cfg["k"] = rng.choice([100000, 10**9])
            a["config"] = np.array(json.dumps(cfg))
        data = _rewrite_npz(base, edit)
    elif kind == "config-json":
        data = _rewrite_npz(base, lambda a: a.__setitem__(
            "config", np.array("[" * 5000 + "]" * 5000)))
    if cmd == "resume":
        argv = ["train", scenario, "--method", method, "--episodes", "40", "--resume", "a.npz"]
    else:
        argv = ["route", scenario, "--agent", "a.npz"]

    def setup(d: Path) -> None:
        if kind == "fifo":
            os.mkfifo(d / "a.npz")
        elif kind == "dir":
            (d / "a.npz").mkdir()
        else:
            (d / "a.npz").write_bytes(data)
    return Case(f"checkpoint:{kind}:{cmd}", argv, expect, setup)


# ---------------------------------------------------------------- resume state
SWEEP = ["compare", "paper-50", "--methods", "st-ql", "--seeds", "1", "--episodes", "5",
         "--jobs", "1", "--out", "out"]


def resume_case(rng: random.Random) -> Case:
    kind = rng.choice(["list", "empty-obj", "null", "bytes", "nan", "partial-dir",
                       "results-dir", "results-bad", "lock-dir", "lock-junk", "number"])
    expect = "error2"
    check = _no_nan("out")

    def setup(d: Path) -> None:
        out = d / "out"
        out.mkdir()
        partial = out / "runs.partial.jsonl"
        if kind == "list":
            partial.write_text("[1, 2]\n")
        elif kind == "empty-obj":
            partial.write_text("{}\n")
        elif kind == "null":
            partial.write_text("null\n")
        elif kind == "number":
            partial.write_text("17\n")
        elif kind == "bytes":
            partial.write_bytes(b'{"key": "\xff\xfe"}\n')
        elif kind == "nan":
            partial.write_text('{"key": "x", "success_rate": NaN}\n')
        elif kind == "partial-dir":
            partial.mkdir()
        elif kind == "results-dir":
            (out / "results.json").mkdir()
        elif kind == "results-bad":
            (out / "results.json").write_text(rng.choice(["[1]", "null", '{"runs": 5}',
                                                          '{"runs": [1]}', "\xff"]))
        elif kind == "lock-dir":
            (out / ".rnhql-sweep.lock").mkdir()
        elif kind == "lock-junk":
            (out / ".rnhql-sweep.lock").write_bytes(junk)

    junk = rng.choice([b"\xff\xfe", b"-5", b"1e9", b"99999999999999999999"])
    case = Case(f"resume:{kind}", [*SWEEP, "--resume"], expect, setup, check)
    if kind == "lock-junk":
        case.expect = "ok"
    return case


def _no_nan(out: str) -> Callable[[Path], str | None]:
    def check(d: Path) -> str | None:
        summary = d / out / "summary.md"
        if summary.exists() and "nan" in summary.read_text().lower():
            return "nan in summary.md"
        return None
    return check


# ---------------------------------------------------------------- outputs: paths
def _still_char_device(name: str) -> Callable[[Path], str | None]:
    def check(d: Path) -> str | None:
        p = d / name
        st = os.lstat(p)
        if stat.S_ISLNK(st.st_mode):
            return None
        return None if stat.S_ISCHR(st.st_mode) else f"{name} was replaced by a regular file"
    return check


def path_case(rng: random.Random) -> Case:
    kind = rng.choice(["devnode", "symlink-stdout", "dev-full", "empty", "dir", "fifo",
                       "symlink-devnull"])
    flag = rng.choice(["--json", "--save", "--record", "--png"])
    if flag == "--png":
        base = ["route", "paper-50", "--agent", "a.npz"]
    else:
        base = ["train", "paper-50", *TRAIN]
    suffix = {"--record": ".rrd", "--png": ".png"}.get(flag, "")
    def check(d: Path) -> (str | None):
        return None
    expect = "ok"

    def setup(d: Path) -> None:
        if flag == "--png":
            (d / "a.npz").write_bytes(_base_checkpoint("st-ql"))
        target = d / f"target{suffix}"
        if kind == "devnode":
            os.mknod(target, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        elif kind == "symlink-stdout":
            target.symlink_to("/proc/self/fd/1")
        elif kind == "symlink-devnull":
            target.symlink_to("/dev/null")
        elif kind == "dev-full":
            os.mknod(target, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
        elif kind == "dir":
            target.mkdir()
        elif kind == "fifo":
            os.mkfifo(target)

    value = f"target{suffix}"
    if kind == "empty":
        value, expect = "", "error2"
    elif kind == "dir":
        expect = "error2"
    elif kind == "fifo":
        expect = "ok|error2"
    elif kind == "dev-full":
        expect = "error1"
    if kind in ("devnode", "dev-full"):
        check = _still_char_device(value)
    argv = [*base, flag, value]
    if flag == "--save" and kind in ("devnode", "symlink-stdout", "symlink-devnull"):
        expect = "ok"
    return Case(f"path:{kind}:{flag}", argv, expect, setup, check)


def empty_case(rng: random.Random) -> Case:
    which = rng.choice([["train", "paper-50", *TRAIN, "--resume", ""],
                        ["compare", "paper-50", "--methods", "st-ql", "--seeds", "1",
                         "--episodes", "5", "--jobs", "1", "--out", ""],
                        ["route", "paper-50", "--agent", ""],
                        ["train", "", *TRAIN],
                        ["train", "--scen", "", "--index", "0", *TRAIN],
                        ["scenarios", "--check", ""]])
    return Case("empty:" + which[0] + ":" + next(a for a in which if a.startswith("--")
                                                 or a == ""), which, "error2")


# ---------------------------------------------------------------- numbers on the command line
def number_case(rng: random.Random) -> Case:
    kind = rng.choice(["set", "set", "seed", "aliasing-seed", "episodes", "seeds"])
    if kind == "set":
        fld, method = rng.choice([("k", "rnh-ql"), ("n_planning", "dyna-q"),
                                  ("n_planning", "rnh-ql+"), ("alpha", "st-ql"),
                                  ("warmup_episodes", "rnh-ql"), ("block", "sarsa-rs"),
                                  ("beta", "haql")])
        value = rng.choice(["inf", "-inf", "nan", "1e30", "1e12", "1e308", "-1", "1e6"])
        argv = ["train", "paper-50", "--method", method, "--episodes", "3", "--set",
                f"{fld}={value}"]
        expect = "error2" if value != "1e6" or fld in ("k", "n_planning", "block") else \
            "ok|error2"
        if fld == "alpha" and value == "1e6":
            expect = "error2"
        return Case(f"number:set:{fld}={value}", argv, expect)
    if kind == "seed":
        return Case("number:seed", ["train", "paper-50", *TRAIN, "--seed",
                                    rng.choice(["-1", str(2**64), "-99999999999999999999"])],
                    "error2")
    if kind == "aliasing-seed":
        return Case("number:aliasing-seed", ["aliasing", "paper-50", "--seed",
                                             rng.choice(["-1", "-7"]), "--repeats", "1",
                                             "--out", "al"], "error2")
    if kind == "episodes":
        return Case("number:episodes", ["train", "paper-50", "--method", "st-ql", "--episodes",
                                        rng.choice(["0", "-5", str(10**12)])], "error2")
    return Case("number:seeds", ["compare", "paper-50", "--methods", "st-ql", "--seeds",
                                 rng.choice(["0", str(10**9)]), "--episodes", "5", "--out",
                                 "o"], "error2")


# ---------------------------------------------------------------- caches, env, signals
def cache_case(rng: random.Random) -> Case:
    kind = rng.choice(["truncate", "tamper", "junk", "dir"])

    def setup(d: Path) -> None:
        cache = d / "cache" / "rnhql" / "physics-graph"
        cache.mkdir(parents=True)
        src = _physics_cache_file()
        name = src.name
        raw = src.read_bytes()
        if kind == "truncate":
            (cache / name).write_bytes(raw[: len(raw) // 2])
        elif kind == "junk":
            (cache / name).write_bytes(b"PK\x03\x04" + bytes(200))
        elif kind == "dir":
            (cache / name).mkdir()
        else:
            import io

            import numpy as np
            with np.load(io.BytesIO(raw)) as z:
                arrays = {k: z[k] for k in z.files}
            nxt = arrays["next_state"].copy()
            nxt[:] = int(np.argmax(nxt.max(axis=1)))  # every move lands on one cell
            goal = _paper40_goal()
            nxt[:] = goal
            arrays["next_state"] = nxt
            out = io.BytesIO()
            np.savez(out, **arrays)
            (cache / name).write_bytes(out.getvalue())

    def check(d: Path) -> str | None:
        return None

    argv = ["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes", "3",
            "--world", "physics", "--jobs", "1", "--out", "out"]
    return Case(f"cache:{kind}", argv, "ok", setup, _physics_not_perfect("out")
                if kind == "tamper" else check, env={"XDG_CACHE_HOME": "cache"})


def _paper40_goal() -> int:
    sys.path.insert(0, str(REPO))
    from sim.grid import build_model
    from sim.scenario_io import resolve_scenario

    return int(build_model(resolve_scenario("paper-40")).goal)


def _physics_not_perfect(out: str) -> Callable[[Path], str | None]:
    def check(d: Path) -> str | None:
        import json

        res = d / out / "results.json"
        if not res.exists():
            return None
        runs = json.loads(res.read_text())["runs"]
        if any(r["final_route_length"] == 1 for r in runs):
            return "a tampered cache was believed (a 1-move route)"
        return None
    return check


_PHYS: list[Path] = []


def _physics_cache_file() -> Path:
    if not _PHYS:
        home = Path(tempfile.mkdtemp(prefix="rnhql-probe-cache-"))
        subprocess.run([PY, "-m", "scenarios.cli", "compare", "paper-40", "--methods", "st-ql",
                        "--seeds", "1", "--episodes", "3", "--world", "physics", "--jobs", "1",
                        "--out", str(home / "o")], cwd=REPO, capture_output=True, check=True,
                       env=_env({"XDG_CACHE_HOME": str(home)}))
        _PHYS.append(next((home / "rnhql" / "physics-graph").glob("*.npz")))
    return _PHYS[0]


def signal_case(rng: random.Random) -> Case:
    sig = rng.choice([signal.SIGHUP, signal.SIGHUP, signal.SIGTERM])
    jobs = rng.choice(["1", "2"])
    argv = ["compare", "paper-50", "--methods", "st-ql,q-lambda", "--seeds", "4", "--episodes",
            "30000", "--jobs", jobs, "--out", "out", "--record", "out/c.rrd"]

    def check(d: Path) -> str | None:
        if (d / "out" / ".rnhql-sweep.lock").exists():
            return "the lock was left behind"
        return None
    return Case(f"signal:{signal.Signals(sig).name}:jobs{jobs}", argv, "signal", check=check,
                send=(sig, rng.uniform(3.0, 6.0)))


def env_case(rng: random.Random) -> Case:
    kind = rng.choice(["numba-cache", "scenario-path"])
    if kind == "numba-cache":
        return Case("env:numba-cache", ["train", "paper-50", *TRAIN], "ok",
                    env={"NUMBA_CACHE_DIR": "/tmp/rnhql-probe-numba"}, note="notice")
    return Case("env:scenario-path", ["train", "nope", *TRAIN], "error2",
                env={"RNHQL_SCENARIO_PATH": "/dev/null:/nonexistent"})


def full_disk_case(rng: random.Random) -> Case:
    jobs = rng.choice(["1", "2"])
    record = rng.random() < 0.6
    argv = ["compare", "paper-40", "--methods", "st-ql,q-lambda", "--seeds", "2",
            "--episodes", "300", "--jobs", jobs, "--out", "{mnt}/out"]
    if record:
        argv += ["--record", "{mnt}/c.rrd"]
    return Case(f"full-disk:jobs{jobs}:{'record' if record else 'plain'}", argv, "error1",
                note="tmpfs")


# ---------------------------------------------------------------- round three's classes
VICTIM = "victim.txt"
OWN_NAMES = ["results.json", "summary.md", "runs.partial.jsonl", ".rnhql-sweep.lock",
             "steps_per_episode.png", "greedy_test.png"]


def _victim_untouched(d: Path) -> str | None:
    v = d / VICTIM
    return None if v.read_text() == "keep me" else f"a planted link wrote {VICTIM}"


def link_case(rng: random.Random) -> Case:
    """A link planted in a shared output folder, under a name the tool gives its own files,
    pointing at a file of the user's: it is replaced, never followed."""
    name = rng.choice(OWN_NAMES)

    def setup(d: Path) -> None:
        (d / VICTIM).write_text("keep me")
        (d / "out").mkdir()
        if hard:
            os.link(d / VICTIM, d / "out" / name)
        else:
            (d / "out" / name).symlink_to(d / VICTIM)

    hard = rng.random() < 0.5  # a hard link: the same file under a second name
    argv = [*SWEEP, *(["--resume"] if rng.random() < 0.3 else [])]
    return Case(f"{'hardlink' if hard else 'link'}:{name}", argv, "ok|error2", setup,
                _victim_untouched)


def view_case(rng: random.Random) -> Case:
    """``rnhql view``'s inputs: a file named like a flag, ports out of range, an empty
    recording, a folder, a FIFO, /dev/null. Each is one line, exit 2, and no viewer."""
    kind = rng.choice(["flag-name", "port-high", "port-negative", "empty", "dir", "fifo",
                       "devnull"])
    target = {"flag-name": "--version", "devnull": "/dev/null"}.get(kind, "x.rrd")

    def setup(d: Path) -> None:
        if kind in ("flag-name", "empty", "port-high", "port-negative"):
            (d / target).write_bytes(b"" if kind == "empty" else b"not a recording")
        elif kind == "dir":
            (d / target).mkdir()
        elif kind == "fifo":
            os.mkfifo(d / target)

    argv = ["view", f"./{target}" if kind == "flag-name" else target, "--web"]
    if kind == "port-high":
        argv += ["--port", "65536"]
    elif kind == "port-negative":
        argv += ["--port", "-1"]
    return Case(f"view:{kind}", argv, "error2", setup)


def numba_full_case(rng: random.Random) -> Case:
    """NUMBA_CACHE_DIR on a full disk: numba's cache is named, exit 1."""
    return Case("env:numba-cache-full", ["train", "paper-40", *TRAIN], "error1",
                env={"NUMBA_CACHE_DIR": "{mnt}"}, note="tmpfs")


def obstacles_case(rng: random.Random) -> Case:
    """Random circles that can never all fit (S and G kept clear): an error naming how many
    fit, not a run with fewer."""
    count = rng.choice(["100000", "5000", "2000"])
    text = BASE_TOML.replace("count = 28", f"count = {count}", 1)
    return Case(f"obstacles:count={count}", ["train", "s.toml", *TRAIN], "error2",
                _write("s.toml", text))


GYM_SNIPPETS = {
    "cell-negative": "gym.make('rnhql/GridRoute-v0', scenario=Scenario(**{**base, "
                     "'blocked_cells': ((-1, 0),)}))",
    "cell-outside": "gym.make('rnhql/PhysicsRoute-v0', scenario=Scenario(**{**base, "
                    "'blocked_cells': ((base['width_m'] * 100, 3),)}))",
    "cell-float": "gym.make('rnhql/GridRoute-v0', scenario=Scenario(**{**base, "
                  "'blocked_cells': ((1.5, 2),)}))",
    "friction-nan": "PhysicsConfig(friction=float('nan')).validate()",
    "substeps-huge": "PhysicsConfig(substeps=10**7).validate()",
    "dt-tiny": "PhysicsConfig(dt_s=1e-9).validate()",
    "num-envs-huge": "gym.make_vec('rnhql/GridRoute-v0', num_envs=100000)",
    # values a cast would have made something else of (round four)
    "heading-text": "gym.make('rnhql/DiffDrive-v0', scenario='paper-40').unwrapped.reset("
                    "options={'heading': '1.0'})",
    "heading-bool": "gym.make('rnhql/DiffDrive-v0', scenario='paper-40').unwrapped.reset("
                    "options={'heading': True})",
    "actions-object": "(lambda v: (v.reset(), v.step(np.array([0.5, 1.5], dtype=object))))("
                      "gym.make_vec('rnhql/GridRoute-v0', num_envs=2))",
    "starts-float": "gym.make_vec('rnhql/PhysicsRoute-v0', num_envs=2, vectorization_mode="
                    "'vector_entry_point', scenario='paper-40').reset(options={'starts': "
                    "[3.7, 5.0]})",
    "reset-mask-short": "gym.make_vec('rnhql/PhysicsRoute-v0', num_envs=3, vectorization_mode="
                        "'vector_entry_point', scenario='paper-40').reset(options={"
                        "'reset_mask': [True]})",
}


def gym_case(rng: random.Random) -> Case:
    """What a Gymnasium client hands the envs: each argument checked as the TOML path checks
    it, the same one-line error (the snippet prints it as the CLI would, exit 2)."""
    kind = rng.choice(sorted(GYM_SNIPPETS))
    code = (
        "import dataclasses, sys\n"
        "import gymnasium as gym\n"
        "import numpy as np\n"
        "import sim\n"
        "from sim.errors import InputError\n"
        "from sim.physics.static import PhysicsConfig\n"
        "from sim.scenario import Scenario\n"
        "from sim.scenario_io import resolve_scenario\n"
        "sc = resolve_scenario('paper-40')\n"
        "base = {f.name: getattr(sc, f.name) for f in dataclasses.fields(sc)}\n"
        "try:\n"
        f"    {GYM_SNIPPETS[kind]}\n"
        "except InputError as err:\n"
        "    print(f'rnhql: error: {err}', file=sys.stderr)\n"
        "    sys.exit(2)\n"
        "except ValueError as err:  # an env's option or action: a ValueError naming it\n"
        "    print(f'rnhql: error: {err}', file=sys.stderr)\n"
        "    sys.exit(2 if ('; ' in str(err) or 'must be' in str(err)) else 3)\n")
    return Case(f"gym:{kind}", [], "error2", python=code)


def results_case(rng: random.Random) -> Case:
    """Damaged resume state of the two forms round two found: a run with a string where a
    number goes, a run with only its key."""
    kind = rng.choice(["string-value", "key-only"])
    line = ('{"key": "%s", "final_route_length": "many"}' if kind == "string-value"
            else '{"key": "%s"}')

    def setup(d: Path) -> None:
        out = d / "out"
        out.mkdir()
        from scenarios.sweep.run import make_specs  # the key the sweep will look for

        key = make_specs("paper-50", ["st-ql"], [0], 5, ["grid"])[0].key
        (out / "runs.partial.jsonl").write_text(line % key + "\n")

    return Case(f"resume2:{kind}", [*SWEEP, "--resume"], "ok|error2", setup, _no_nan("out"))


USER_MODULES = {
    "syntax-error": ("def oops(:\n", "error2"),
    "raises-at-import": ("raise RuntimeError('no')\n", "error2"),
    "exits-at-import": ("import sys\nsys.exit(0)\n", "error2"),
    "exits-in-act": (None, "error1"),
    "returns-4": (None, "error1"),
    "returns-float": (None, "error1"),
}


def user_module_case(rng: random.Random) -> Case:
    """A learner module of the user's that misbehaves (``--method mod:Class``): one line
    naming it, exit 2 for a module that cannot be loaded, exit 1 for a run that failed."""
    kind = rng.choice([*sorted(USER_MODULES), "dotted-name", "path-name"])
    body, expect = USER_MODULES.get(kind, (None, "error2"))
    act = {"exits-in-act": "        import sys; sys.exit(0)",
           "returns-4": "        return 4",
           "returns-float": "        return 1.7"}.get(kind, "        return 0")
    learner = ("class L:\n"
               "    def __init__(self, n_states, n_actions, rng):\n"
               "        self.n = n_actions\n"
               "    def act(self, s):\n" + act + "\n"
               "    def update(self, s, a, r, s2, terminal):\n"
               "        pass\n"
               "    def greedy(self, s):\n"
               "        return 0\n")
    name = {"dotted-name": "..mymod:L", "path-name": "./mymod.py:L"}.get(kind, "mymod:L")
    return Case(f"user-module:{kind}", ["train", "paper-40", "--method", name, "--episodes",
                                         "3"], expect,
                _write("mymod.py", body if body is not None else learner))


def lock_pid_case(rng: random.Random) -> Case:
    """A lock file naming a live process that holds no lock (pid 1): the folder is free."""
    def setup(d: Path) -> None:
        (d / "out").mkdir()
        (d / "out" / ".rnhql-sweep.lock").write_text(f"{rng.choice([1, os.getpid()])}\n")

    return Case("lock:live-pid", SWEEP, "ok", setup)


def edited_run_case(rng: random.Random) -> Case:
    """A finished sweep whose results.json names another method, world or seed for a run:
    ``--resume`` refuses it rather than show a run that never happened."""
    field_, value = rng.choice([("method", "fake-method"), ("seed", 99), ("world", "physics")])

    def setup(d: Path) -> None:
        subprocess.run([PY, "-m", "scenarios.cli", *SWEEP], cwd=d, capture_output=True,
                       env=_env({}))
        results = d / "out" / "results.json"
        import json

        doc = json.loads(results.read_text())
        doc["runs"][0][field_] = value
        results.write_text(json.dumps(doc))

    return Case(f"resume-edited:{field_}", [*SWEEP, "--resume"], "error2", setup)


def address_space_case(rng: random.Random) -> Case:
    """An address-space limit (``ulimit -v``): too small to compile is one line, a
    recording below Rerun's need is refused before training, a run above the floor ends."""
    kind, limit_mb, argv, expect = rng.choice([
        ("tiny", 300, ["train", "paper-40", *TRAIN], "error1"),
        ("record", 2000, ["train", "paper-40", *TRAIN, "--record", "x.rrd"], "error2"),
        ("enough", 1200, ["train", "paper-40", *TRAIN], "ok"),
    ])
    return Case(f"ulimit:{kind}", argv, expect, limit_bytes=limit_mb * 1024 * 1024)


GENERATORS = [(toml_case, 4), (map_case, 2), (scen_case, 2), (checkpoint_case, 3),
              (resume_case, 3), (path_case, 3), (empty_case, 1), (number_case, 2),
              (cache_case, 1), (signal_case, 1), (env_case, 1), (full_disk_case, 1),
              (link_case, 2), (view_case, 2), (numba_full_case, 1), (obstacles_case, 1),
              (gym_case, 2), (results_case, 1), (user_module_case, 2), (lock_pid_case, 1),
              (edited_run_case, 1), (address_space_case, 1)]


def _env(extra: dict[str, str]) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR",)}
    env.update(PYTHONPATH=str(REPO), RNHQL_NO_OPTIMUM="1", PYTHONUNBUFFERED="1")
    env.update(extra)
    return env


def _terminal_signals(limit_bytes: int | None = None) -> None:
    """In the case's process: SIGINT and SIGHUP as a terminal session has them, whatever
    the probe inherited (started with nohup, or in the background, they are ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    if limit_bytes is not None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))


def run_case(case: Case, work: Path, timeout: float) -> tuple[str, str]:
    """(category, detail) of one case run in its own folder."""
    d = Path(tempfile.mkdtemp(prefix="case-", dir=work))
    mnt = None
    if case.note == "tmpfs":
        mnt = d / "mnt"
        mnt.mkdir()
        if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mnt)],
                          capture_output=True).returncode != 0:
            return "skipped", "cannot mount a tmpfs"
        with open(mnt / "filler", "wb") as f:
            f.write(b"\0" * (2048 - 60) * 1024)
        case.argv = [a.replace("{mnt}", str(mnt)) for a in case.argv]
        case.env = {k: v.replace("{mnt}", str(mnt)) for k, v in case.env.items()}
    try:
        case.setup(d)
        env = _env({k: (str(d / v) if k == "XDG_CACHE_HOME" else v)
                    for k, v in case.env.items()})
        env["HOME"] = str(d)
        argv = [PY, "-c", case.python] if case.python else [PY, "-m", "scenarios.cli",
                                                               *case.argv]
        proc = subprocess.Popen(argv, cwd=d,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                encoding="utf-8", errors="replace", env=env,
                                start_new_session=True,  # (a PNG may go to stdout)
                                preexec_fn=functools.partial(_terminal_signals,
                                                             case.limit_bytes))
        try:
            if case.send is not None:
                time.sleep(case.send[1])
                proc.send_signal(case.send[0])
            out, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            return "hang", f"no exit within {timeout:.0f} s"
        except BaseException:  # the probe itself stopped: never leave its case running
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            raise
        rc = proc.returncode
        return _classify(case, rc, out, err, d)
    finally:
        if mnt is not None:
            subprocess.run(["umount", "-l", str(mnt)], capture_output=True)
        shutil.rmtree(d, ignore_errors=True)


def _classify(case: Case, rc: int, out: str, err: str, d: Path) -> tuple[str, str]:
    tail = err.strip().splitlines()[-1:] or [""]
    if "Traceback" in err:
        return "traceback", tail[0][:200]
    if rc < 0 or rc not in (0, 1, 2, 129, 130, 143):
        return "crash", f"status {rc}: {tail[0][:200]}"
    problem = case.check(d)
    if problem:
        return "silent", problem
    errors = [ln for ln in err.splitlines() if ln.startswith("rnhql: error")]
    failed = [ln for ln in err.splitlines() if ln.startswith("rnhql: the run failed: ")]
    if rc == 1 and not errors and len(failed) == 1:  # a user's learner failed: named, once
        return ("clean", "") if case.expect in ("error1", "ok|error1") else (
            "wrong exit", f"a failed run where {case.expect} was expected: {failed[0][:160]}")
    if case.note == "notice" and "compiling the numba kernels" in err:
        # the second of two runs with the same cache must not announce a compilation
        return "silent", "the compile notice printed on a cached run"
    if case.expect == "signal":
        if rc in (129, 143) and "Traceback" not in err:
            return "clean", ""
        return "wrong exit", f"status {rc} after {case.send}: {tail[0][:160]}"
    allowed = {"ok": {0}, "error2": {2}, "error1": {1}, "ok|error2": {0, 2},
               "ok|error1": {0, 1}}[case.expect]
    if rc == 0 and 0 not in allowed:
        return "silent", "exit 0 on input that should be refused"
    if rc not in allowed:
        return "wrong exit", f"status {rc} (expected {case.expect}): {tail[0][:160]}"
    if rc != 0 and (len(errors) != 1 or not ("Fix" in errors[0] or "; " in errors[0])):
        return "wrong exit", f"not one clear line: {tail[0][:160]}"
    if rc == 1 and "no space left" not in err.lower() and case.note == "tmpfs":
        return "wrong exit", f"full disk not named: {tail[0][:160]}"
    return "clean", ""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", type=int, default=120)
    ap.add_argument("--timeout", type=float, default=90.0)
    ap.add_argument("--show", action="store_true")
    ap.add_argument("--only", default=None, help="only cases whose kind starts with this")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    gens = [g for g, w in GENERATORS for _ in range(w)]
    cases = [rng.choice(gens)(rng) for _ in range(args.cases)]
    if args.only:
        cases = [c for c in cases if c.kind.startswith(args.only)]
    # a cached-kernels notice case needs a warm cache first
    if any(c.note == "notice" for c in cases):
        subprocess.run([PY, "-m", "scenarios.cli", "train", "paper-50", *TRAIN], cwd=REPO,
                       capture_output=True, env=_env({"NUMBA_CACHE_DIR":
                                                      "/tmp/rnhql-probe-numba"}))
    work = Path(tempfile.mkdtemp(prefix="rnhql-probe-"))
    # SIGTERM to the probe: end the case running (its own session) and unmount, then exit
    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))
    tally: collections.Counter[str] = collections.Counter()
    t0 = time.time()
    for i, case in enumerate(cases):
        cat, detail = run_case(case, work, args.timeout)
        tally[cat] += 1
        if args.show and cat != "clean":
            print(f"[{i}] {cat:<10} {case.kind:<34} {' '.join(case.argv)[:90]}\n"
                  f"      {detail}", flush=True)
    shutil.rmtree(work, ignore_errors=True)
    print(f"seed {args.seed}, {len(cases)} cases in {time.time() - t0:.0f} s: " + ", ".join(
        f"{k} {tally.get(k, 0)}" for k in ("clean", "traceback", "hang", "crash", "silent",
                                           "wrong exit", "skipped")))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

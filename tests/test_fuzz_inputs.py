"""Property: any scenario TOML, ``.map``, ``.scen`` or checkpoint gives either a valid run or
one line and exit 2, never a traceback.

Hypothesis draws the inputs (values from pools of hostile kinds: inf,
NaN, 1e308, 46-digit integers, negative seeds, deep nesting, stray bytes, truncated
files, tampered arrays) and the CLI's ``main`` runs each in-process with a two-episode
budget. A bug shows as an exception escaping ``main`` (what a user would see as a
traceback), a status other than 0 or 2, or a refusal that is not one line. The default
run draws a few hundred inputs in all; ``-m slow`` draws thousands.
"""

from __future__ import annotations

import contextlib
import io
import json
import tempfile
import uuid
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scenarios.cli import main

FAST = settings(max_examples=80, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])
SLOW = settings(max_examples=1500, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="rnhql-fuzz-"))


def run(argv: list[str]) -> tuple[int, str]:
    """``main(argv)`` with its output captured; (status, stderr)."""
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's usage errors (one line, exit 2)
            code = exc.code if isinstance(exc.code, int) else 1
    return code, err.getvalue()


def assert_valid_run_or_one_line(argv: list[str]) -> None:
    code, err = run(argv)
    assert code in (0, 2), (code, err)
    if code == 2:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert len(lines) == 1 and lines[0].startswith("rnhql: error:"), err


def fresh(suffix: str) -> Path:
    """A new file name per example: loaded scenarios are cached by name."""
    return WORK / f"{uuid.uuid4().hex}{suffix}"


# ------------------------------------------------------------------ scenario TOML
NUMBERS = ["0", "1", "-1", "2", "3.5", "40", "40.0", "8.0", "0.3", "1e-9", "1e308", "-1e308",
           "inf", "-inf", "nan", "1" * 46, str(2**64), "-0.0", "true", '"text"', "[]",
           "[1, 2]", "{}"]
KEYS = {
    "": ["start", "goal", "steps_per_episode", "s_start_share", "name", "bogus"],
    "arena": ["width_m", "height_m", "cell_size_m", "map"],
    "robot": ["radius_m", "clearance_m", "mass_kg", "wheel_base_m"],
    "rewards": ["goal", "bump", "step", "scheme"],
    "obstacles.random": ["count", "radius_min_m", "radius_max_m", "seed"],
}
BASE = {"": {"name": '"f"', "start": "[1, 1]", "goal": "[6, 6]", "steps_per_episode": "60"},
        "arena": {"width_m": "8.0", "height_m": "8.0", "cell_size_m": "1.0"},
        "robot": {}, "rewards": {},
        "obstacles.random": {"count": "2", "radius_min_m": "0.5", "radius_max_m": "1.0",
                             "seed": "3"}}
CELLS = ["[1, 1]", "[6, 6]", "[-1, 0]", "[0]", "[99, 99]", "[1.5, 2]", '["a", 1]', "[1, 1, 1]"]


@st.composite
def scenario_toml(draw) -> bytes:
    tables = {t: dict(v) for t, v in BASE.items()}
    for _ in range(draw(st.integers(0, 4))):
        table = draw(st.sampled_from(sorted(KEYS)))
        key = draw(st.sampled_from(KEYS[table]))
        pool = CELLS if key in ("start", "goal") else NUMBERS + (
            ['"/dev/zero"', '"missing.map"', '""'] if key == "map" else []) + (
            ['"paper"', '"nope"'] if key == "scheme" else [])
        tables[table][key] = draw(st.sampled_from(pool))
    for _ in range(draw(st.integers(0, 2))):  # drop a key or a whole table
        table = draw(st.sampled_from(sorted(tables)))
        if tables[table] and draw(st.booleans()):
            tables[table].pop(draw(st.sampled_from(sorted(tables[table]))))
        elif table:
            tables.pop(table)
    if draw(st.booleans()):
        spacing = draw(st.sampled_from(["1.0", "1e-9", "0", "-1", "inf", "1e-300"]))
        end = draw(st.sampled_from(["[8.0, 8.0]", "[1e308, 1e308]", "[3.0, 3.0]"]))
        tables["chain"] = {"from": "[0.0, 0.0]", "to": end, "radius_m": "0.4",
                           "spacing_m": spacing}
    lines = [f"{k} = {v}" for k, v in tables.pop("").items()]
    chain = tables.pop("chain", None)
    for name, kv in tables.items():
        lines += [f"[{name}]", *(f"{k} = {v}" for k, v in kv.items())]
    if chain is not None:
        lines += ["[[obstacles.chains]]", *(f"{k} = {v}" for k, v in chain.items())]
    text = "\n".join(lines) + "\n"
    if draw(st.booleans()):
        depth = draw(st.sampled_from([3, 200, 5000]))
        text += "deep = " + "[" * depth + "]" * depth + "\n"
    raw = text.encode()
    if draw(st.integers(0, 4)) == 0:  # stray bytes or a cut
        at = draw(st.integers(0, len(raw)))
        raw = raw[:at] + draw(st.binary(max_size=8)) + (raw[at:] if draw(st.booleans())
                                                         else b"")
    return raw


def check_scenario(raw: bytes) -> None:
    path = fresh(".toml")
    path.write_bytes(raw)
    assert_valid_run_or_one_line(["train", str(path), "--method", "st-ql", "--episodes", "2"])


@FAST
@given(scenario_toml())
def test_any_scenario_toml_runs_or_is_one_line(raw):
    check_scenario(raw)


@pytest.mark.slow
@SLOW
@given(scenario_toml())
def test_any_scenario_toml_runs_or_is_one_line_many(raw):
    check_scenario(raw)


# ------------------------------------------------------------------ .map
@st.composite
def map_file(draw) -> tuple[bytes, str, str]:
    h, w = draw(st.integers(1, 8)), draw(st.integers(1, 8))
    head_h = draw(st.sampled_from([str(h), str(h + 1), "0", "-2", "x", "99999999", "5000"]))
    head_w = draw(st.sampled_from([str(w), "0", "8.5", "99999999"]))
    rows = ["".join(draw(st.lists(st.sampled_from(".@GSTOW#\t é"), min_size=w, max_size=w)))
            for _ in range(h)]
    kind = draw(st.sampled_from(["octile", "octile", "hex", ""]))
    text = f"type {kind}\nheight {head_h}\nwidth {head_w}\nmap\n" + "\n".join(rows) + "\n"
    raw = text.encode()
    if draw(st.integers(0, 3)) == 0:
        raw = raw[: draw(st.integers(0, len(raw)))] + draw(st.binary(max_size=6))
    start = f"{draw(st.integers(-1, 8))},{draw(st.integers(-1, 8))}"
    goal = f"{draw(st.integers(-1, 8))},{draw(st.integers(-1, 8))}"
    return raw, start, goal


def check_map(args: tuple[bytes, str, str]) -> None:
    raw, start, goal = args
    path = fresh(".map")
    path.write_bytes(raw)
    assert_valid_run_or_one_line(["train", str(path), f"--start={start}", f"--goal={goal}",
                                  "--method", "st-ql", "--episodes", "2"])


@FAST
@given(map_file())
def test_any_map_runs_or_is_one_line(args):
    check_map(args)


@pytest.mark.slow
@SLOW
@given(map_file())
def test_any_map_runs_or_is_one_line_many(args):
    check_map(args)


# ------------------------------------------------------------------ .scen
SCEN_FIELDS = ["0", "1", "-1", "7", "8", "9", "99999999999", "x", "nan", "inf", "1e400", "2.5"]


@st.composite
def scen_file(draw) -> tuple[bytes, str]:
    lines = [draw(st.sampled_from(["version 1", "version 1.0", "version 2", "", "v"]))]
    for _ in range(draw(st.integers(0, 3))):
        fields = [draw(st.sampled_from(SCEN_FIELDS)),
                  draw(st.sampled_from(["m.map", "../m.map", "/dev/zero", "nope.map", "m.txt"])),
                  *(draw(st.sampled_from(["8", *SCEN_FIELDS])) for _ in range(6)),
                  draw(st.sampled_from(SCEN_FIELDS))]
        if draw(st.integers(0, 5)) == 0:
            fields = fields[: draw(st.integers(0, 8))]
        lines.append("\t".join(fields))
    raw = ("\n".join(lines) + "\n").encode()
    if draw(st.integers(0, 4)) == 0:
        raw += draw(st.binary(min_size=1, max_size=6))
    return raw, draw(st.sampled_from(["0", "1", "-1", "99"]))


def check_scen(args: tuple[bytes, str]) -> None:
    raw, index = args
    folder = WORK / uuid.uuid4().hex
    folder.mkdir()
    (folder / "m.map").write_text("type octile\nheight 8\nwidth 8\nmap\n" + "........\n" * 8)
    (folder / "p.scen").write_bytes(raw)
    assert_valid_run_or_one_line(["train", "--scen", str(folder / "p.scen"), f"--index={index}",
                                  "--method", "st-ql", "--episodes", "2"])


@FAST
@given(scen_file())
def test_any_scen_runs_or_is_one_line(args):
    check_scen(args)


@pytest.mark.slow
@SLOW
@given(scen_file())
def test_any_scen_runs_or_is_one_line_many(args):
    check_scen(args)


# ------------------------------------------------------------------ checkpoints
_AGENTS: dict[str, bytes] = {}


def agent_bytes(method: str) -> bytes:
    if method not in _AGENTS:
        path = WORK / f"base-{method}.npz"
        code, err = run(["train", "paper-40", "--method", method, "--episodes", "12",
                         "--save", str(path)])
        assert code == 0, err
        _AGENTS[method] = path.read_bytes()
    return _AGENTS[method]


class Blob(bytes):
    """A drawn file's bytes with a short repr (what was done to it), for Hypothesis' report."""

    what = ""

    def __repr__(self) -> str:
        return f"<{len(self)} bytes: {self.what}>"


def blob(data: bytes, what: str) -> Blob:
    b = Blob(data)
    b.what = what
    return b


ODD_VALUES = [np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0, 1.0, 2**62]


@st.composite
def checkpoint(draw) -> tuple[bytes, str, str]:
    method = draw(st.sampled_from(["st-ql", "rnh-ql", "dyna-q"]))
    raw = agent_bytes(method)
    kind = draw(st.sampled_from(["field", "drop", "value", "truncate", "flip", "json",
                                 "none"]))
    name = ""
    if kind in ("truncate", "flip"):
        data = bytearray(raw)
        if kind == "truncate":
            data = data[: draw(st.integers(0, len(data)))]
        else:
            for _ in range(draw(st.integers(1, 6))):
                data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
        out = bytes(data)
    elif kind == "none":
        out = raw
    else:
        name = ""
        with np.load(io.BytesIO(raw)) as z:
            arrays = {k: z[k] for k in z.files}
        name = draw(st.sampled_from(sorted(arrays)))
        if kind == "drop":
            arrays.pop(name)
        elif kind == "value" and arrays[name].dtype.kind in "fiu" and arrays[name].size:
            arr = arrays[name].astype(np.float64 if arrays[name].dtype.kind == "f"
                                      else arrays[name].dtype).copy()
            value = draw(st.sampled_from(ODD_VALUES))
            flat = arr.reshape(-1)
            i = draw(st.integers(0, flat.size - 1))
            if arr.dtype.kind == "f":
                flat[i] = value
            else:  # the odd value as near as the integer dtype holds
                top = int(np.iinfo(arr.dtype).max)
                flat[i] = min(int(abs(value)), top) if np.isfinite(value) else -1
            arrays[name] = arr
        elif kind == "json" and name in ("config", "rng_state", "problem"):
            arrays[name] = np.array(draw(st.sampled_from(
                ["[]", "null", "{", "[" * 3000 + "]" * 3000, '{"k": 1e999}',
                json.dumps({"k": 100000, "eps": 0.1})])))
        else:  # any field replaced by an array of another shape or dtype
            shape = tuple(draw(st.lists(st.integers(0, 5), max_size=3)))
            dtype = draw(st.sampled_from([np.float64, np.int32, np.bool_, np.float32]))
            arrays[name] = np.zeros(shape, dtype=dtype)
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        out = buf.getvalue()
    command = draw(st.sampled_from(["route", "resume"]))
    what = f"{method} {kind}" + (f" {name}" if kind in ("drop", "value", "json", "field")
                                 else "")
    return blob(out, what), method, command


def check_checkpoint(args: tuple[bytes, str, str]) -> None:
    data, method, command = args
    path = fresh(".npz")
    path.write_bytes(data)
    if command == "route":
        argv = ["route", "paper-40", "--agent", str(path)]
    else:
        argv = ["train", "paper-40", "--method", method, "--episodes", "14", "--resume",
                str(path)]
    assert_valid_run_or_one_line(argv)


@FAST
@given(checkpoint())
def test_any_checkpoint_runs_or_is_one_line(args):
    check_checkpoint(args)


@pytest.mark.slow
@SLOW
@given(checkpoint())
def test_any_checkpoint_runs_or_is_one_line_many(args):
    check_checkpoint(args)


def test_the_strategies_reach_both_outcomes():
    """The property is not vacuous: some drawn inputs run, others are refused."""
    assert run(["train", "paper-40", "--method", "st-ql", "--episodes", "2"])[0] == 0
    good = fresh(".npz")
    good.write_bytes(agent_bytes("st-ql"))
    assert run(["route", "paper-40", "--agent", str(good)])[0] == 0
    bad = fresh(".npz")
    with zipfile.ZipFile(bad, "w") as z:
        z.writestr("format.npy", b"junk")
    assert run(["route", "paper-40", "--agent", str(bad)])[0] == 2

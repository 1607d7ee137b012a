"""The short tour of docs/usage.md, run as a newcomer runs it: every line, its time, its exit.

    python -m scenarios.studies.tour --artifact this-machine
    python -m scenarios.studies.tour --installed      # from a non-editable copy (pip install)

Each line of :data:`TOUR` runs in a fresh folder, in order (a line may use what an earlier
one wrote: the saved agent, the example scenario), with ``HOME`` in that folder so the
user's own files the tour mentions (``my.toml``, ``~/my-scenarios``, ``my.map``) are made
there first. A line passes when it exits as expected (0; ``rnhql report`` in an installed
copy refuses in one line, exit 2: the artifacts live in the source tree) and prints no
traceback, and where its note makes a claim (``shows``), its output bears the claim out (the
default method's greedy route is optimal, the paper's rewards do not reach G, ...).
``--installed`` builds a copy with ``pip install --no-deps --target`` and runs
every line against it, away from the checkout: what ``pip install .`` gives a user.

The docs' tour block is rendered from the artifact, each line with its measured time.
"""

from __future__ import annotations

import itertools
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from scenarios.artifacts import ROOT, write_artifact
from scenarios.script_args import arg, artifact_arg, parse


@dataclass(frozen=True)
class Line:
    """One tour line: the command as the docs print it, what to expect, and what it needs."""

    command: str
    note: str
    own_file: bool = False  # needs the user's own file (made by the tour from the example)
    runs: bool = True  # False: opens a viewer, not run here
    shows: str = ""  # a regular expression the output must match: the note's claim, checked


OPTIMAL = r"final greedy route\s+(\d+) \(optimal \1\)"  # the greedy route is the optimum


MAIN_JOB = ("rnhql compare paper-50 --rewards goal-only --seeds 10 --episodes 3000 --out "
            "results/paper-50 --record")  # the README's set-up step 1, after the install
TOUR = (
    Line(MAIN_JOB, "set-up step 1's main job: every method x 10 seeds, recorded",
         shows=r"(?s)130 runs on paper-50.*recording: recordings/paper-50-compare\.rrd"),
    Line("rnhql scenarios", "named scenarios: size, free cells, optimal route",
         shows=r"paper-50"),
    Line("rnhql train paper-50", "rnh-ql+ (the default method), goal-only rewards (the "
         "default): optimal route in a few dozen episodes",
         shows=r"(?s)stable optimal after  \d\d? episodes.*" + OPTIMAL),
    Line("rnhql train maze-1", "the suite's maps are named scenarios too; rnh-ql+ again finds "
         "the optimal route", shows=OPTIMAL),
    Line("rnhql train paper-50 --method rnh-ql --rewards paper", "the paper's method and "
         "rewards: \"G not reached\" is expected (finding 1)",
         shows=r"final greedy route\s+G not reached"),
    Line("rnhql train paper-50 --method rnh-ql", "... with goal-only rewards it gets there, "
         "late (thousands of episodes)",
         shows=r"(?s)stable optimal after  \d{4} episodes.*" + OPTIMAL),
    Line("rnhql scenarios --example > my.toml", "a complete scenario file, every field "
         "commented"),
    Line("rnhql scenarios --check my.toml", "validate your own scenario", own_file=True),
    Line("RNHQL_SCENARIO_PATH=~/my-scenarios rnhql scenarios", "folders of your own NAME.toml "
         "files add names", own_file=True),
    Line("rnhql scenarios --check my.map --start 3,43 --goal 45,5", "a Moving AI map, its "
         "frame y down", own_file=True),
    Line("rnhql train paper-50 --seed 0 --save agent.npz --record", "one run, saved and "
         "recorded"),
    Line("rnhql train paper-50 --episodes 6000 --resume agent.npz", "continue it exactly",
         shows=r"resuming agent\.npz: 3000 of 6000 episodes done"),
    Line("rnhql route paper-50 --agent agent.npz --png route.png", "greedy route vs BFS "
         "optimum"),
    Line("rnhql route paper-50 --agent agent.npz --world physics", "drive a grid-learned "
         "policy", shows=r"driven in physics at exact: P\(G\) 1\.00"),
    Line("rnhql train paper-50 --world physics --episodes 300", "learn in physics (rnh-ql+ "
         "reaches G)", shows=r"final greedy route\s+\d+ \(optimal"),
    Line("rnhql compare paper-50 --methods rnh-ql+,rnh-ql,st-ql,dyna-q --world grid,physics "
         "--seeds 3 --out out/", "grid and physics side by side"),
    Line("rnhql compare paper-50 --methods rnh-ql+,haql --world physics --fidelity noisy "
         "--episodes 1000 --out out/noisy", "a rung above exact"),
    Line("rnhql aliasing paper-50 --fidelity noisy --out out/aliasing", "next-cell "
         "distributions", shows=r"multi_outcome_fraction 0\.\d+"),
    Line("rnhql optimum paper-50 --fidelity noisy --rollouts 1000", "V*: the optimum at a "
         "fidelity (built once, then cached)", shows=r"V\*\(S\)\s+\d+\.\d+ expected"),
    Line("rnhql compare paper-50 --set alpha=0.2 --out out/alpha-0.2", "override a config "
         "field"),
    Line("rnhql compare paper-50 --rewards paper --out out/p", "or step-cost, "
         "goal=..,bump=..,step=.., scenario"),
    Line("rnhql train --scen arena.map.scen --bucket 12", "a Moving AI problem", own_file=True),
    Line("rnhql view recordings/paper-50-rnh-ql+-grid-s0.rrd [--web]", "open a recording "
         "(a viewer: not run by the tour)", runs=False),
    Line("rnhql bench [--physics] [--json]", "the learners' and the worlds' speed"),
    Line("rnhql report [--figures] [--refresh]", "the docs' tables and figures: fresh or "
         "stale (in a clone; an installed copy says so in one line)"),
)
TRACEBACK = "Traceback (most recent call last)"


def _own_files(home: Path, package_root: Path) -> None:
    """The user's own files the tour names: ~/my-scenarios (the example scenario under a
    name), a Moving AI map with S at (3, 43) and G at (45, 5), and a .map with its .scen."""
    (home / "my-scenarios").mkdir()
    example = subprocess.run([sys.executable, "-m", "scenarios.cli", "scenarios", "--example"],
                             capture_output=True, text=True, check=True,
                             env=_env(home, package_root), cwd=home).stdout
    (home / "my-scenarios" / "my-arena.toml").write_text(example)
    rows = ["." * 49 for _ in range(49)]
    rows[24] = "." * 10 + "@" * 29 + "." * 10  # one wall across the middle
    (home / "my.map").write_text("type octile\nheight 49\nwidth 49\nmap\n" + "\n".join(rows)
                                 + "\n")
    maps = package_root / "sim" / "builtin" / "maps"
    for name in ("arena.map", "arena.map.scen"):
        shutil.copyfile(maps / name, home / name)


def _env(home: Path, package_root: Path) -> dict[str, str]:
    env = dict(os.environ, HOME=str(home), PYTHONPATH=str(package_root),
               MPLBACKEND="Agg", COLUMNS="100", PYTHONUNBUFFERED="1")  # lines as a
    #   terminal shows them, so the silences measured are the user's
    env.pop("RNHQL_SCENARIO_PATH", None)
    return env


def _argv(line: Line, home: Path) -> tuple[list[str], dict[str, str], Path | None]:
    """The line as a process: argv (optional parts in brackets dropped), extra environment,
    and the file its ``>`` writes to."""
    words = line.command.split()
    extra: dict[str, str] = {}
    while "=" in words[0]:
        key, _, value = words.pop(0).partition("=")
        extra[key] = value.replace("~", str(home))
    out = None
    if ">" in words:
        at = words.index(">")
        out, words = home / words[at + 1], words[:at]
    words = [w for w in words if not w.startswith("[")]
    assert words[0] == "rnhql"
    return [sys.executable, "-m", "scenarios.cli", *words[1:]], extra, out


@dataclass(frozen=True)
class Finished:
    """A line's process, run to its end: what it printed, how long it took, and the longest
    time it printed nothing (from its start to its first line, between lines, and from its
    last line to its exit) [s]."""

    returncode: int
    stdout: str
    stderr: str
    wall_s: float
    silence_s: float


def _run_timed(argv: list[str], cwd: Path, env: dict[str, str]) -> Finished:
    """Run ``argv``, noting when each line of its output arrives (both streams)."""
    stamps: list[float] = []
    lock = threading.Lock()
    t0 = time.perf_counter()

    def read(stream: Any, into: list[str]) -> None:
        for text in stream:
            with lock:
                stamps.append(time.perf_counter())
            into.append(text)

    out: list[str] = []
    err: list[str] = []
    with subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, bufsize=1) as proc:
        readers = [threading.Thread(target=read, args=(proc.stdout, out)),
                   threading.Thread(target=read, args=(proc.stderr, err))]
        for r in readers:
            r.start()
        code = proc.wait()
        for r in readers:
            r.join()
    end = time.perf_counter()
    times = [t0, *sorted(stamps), end]
    return Finished(code, "".join(out), "".join(err), end - t0,
                    max(b - a for a, b in itertools.pairwise(times)))


def run_tour(package_root: Path, installed: bool) -> list[dict[str, object]]:
    """Every runnable line in a fresh folder: its wall time [s], exit status, the longest it
    printed nothing [s], whether it passed, and the last line it printed to stderr when it
    did not."""
    rows = []
    with tempfile.TemporaryDirectory(prefix="rnhql-tour-") as tmp:
        home = Path(tmp)
        _own_files(home, package_root)
        for line in TOUR:
            if not line.runs:
                rows.append({"command": line.command, "ran": False})
                continue
            argv, extra, out = _argv(line, home)
            expected = 2 if installed and line.command.startswith("rnhql report") else 0
            proc = _run_timed(argv, home, {**_env(home, package_root), **extra})
            if out is not None:
                out.write_text(proc.stdout)
            said = re.search(line.shows, proc.stdout + proc.stderr) is not None \
                if line.shows else None
            passed = (proc.returncode == expected and TRACEBACK not in proc.stderr
                      and said is not False)
            tail = (proc.stderr.strip().splitlines() or [""])[-1]
            wall = proc.wall_s
            rows.append({"command": line.command, "ran": True, "wall_s": round(wall, 1),
                         "exit": proc.returncode, "passed": passed, "note_checked": said,
                         "longest_silence_s": round(proc.silence_s, 1),
                         **({} if passed else {"stderr": tail[-300:]})})
            print(f"{'ok ' if passed else 'FAIL'} {wall:7.1f} s  exit {proc.returncode}  "
                  f"silent at most {proc.silence_s:4.1f} s  {line.command}", flush=True)
    return rows


def installed_copy(target: Path) -> Path:
    """A non-editable copy of the package (``pip install --no-deps --target``), as a wheel
    installs it: no docs/, no tests/, no checkout around it."""
    source = target.parent / "source"  # pip builds in the source folder: not in the checkout
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        if (ROOT / name).is_file():
            source.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(ROOT / name, source / name)
    for package in ("sim", "learning", "scenarios"):
        shutil.copytree(ROOT / package, source / package,
                        ignore=shutil.ignore_patterns("__pycache__"))
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--target", str(target), str(source)], check=True)
    return target


@dataclass(frozen=True)
class Args:
    installed: bool = arg(False, "run the tour against a non-editable copy (pip install)")
    artifact: str | None = artifact_arg("tour")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    with tempfile.TemporaryDirectory(prefix="rnhql-installed-") as tmp:
        root = installed_copy(Path(tmp) / "site") if args.installed else ROOT
        rows = run_tour(root, args.installed)
    failed = [r for r in rows if r["ran"] and not r["passed"]]
    total = sum(float(r.get("wall_s", 0.0)) for r in rows)
    print(f"{len(rows) - len(failed)} of {len(rows)} lines as expected, {total:.0f} s in all")
    if args.artifact:
        write_artifact(f"tour.{args.artifact}", "python -m scenarios.studies.tour"
                       + (" --installed" if args.installed else "")
                       + f" --artifact {args.artifact}", [],
                       {"installed": args.installed, "lines": rows, "main_job": MAIN_JOB,
                        "notes": {ln.command: ln.note for ln in TOUR},
                        "own_file": [ln.command for ln in TOUR if ln.own_file]},
                       study=__file__)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

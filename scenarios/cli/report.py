"""``rnhql report``: which figures in the docs are stale, and a one-command refresh.

Every generated table in the README and ``docs/`` comes from an artifact in
``docs/results/`` (:mod:`scenarios.artifacts`). ``rnhql report`` lists them with when
and at which code version they were measured, what they took, and whether the code's
behaviour has changed since (stale), and the tables still typed by hand. ``--refresh``
re-runs the command of every stale artifact, one after another (each is a study that
uses every core), then redraws the figures and regenerates the pages (``cog -r``).
``--figures`` redraws every ``docs/`` figure from its artifacts
(:mod:`scenarios.artifacts.figures`).
``--dry-run`` says what a refresh would run and how long it took last time.
"""

from __future__ import annotations

import argparse
import re
import shlex
import subprocess
import sys
from pathlib import Path

from scenarios.artifacts import (
    RESULTS_DIR,
    ROOT,
    ArtifactError,
    artifact_names,
    behaviour_digests,
    generated_pages,
    legacy_tables,
    load_artifact,
    require_checkout,
    stale_parts,
)
from scenarios.artifacts.prose import unbacked_in_docs


def _took(wall_s: float | None) -> str:
    if wall_s is None:
        return "unknown"
    return f"{wall_s / 60:.0f} min" if wall_s >= 90 else f"{wall_s:.0f} s"


# rnhql subcommands that write artifacts
ARTIFACT_SUBCOMMANDS = ("aliasing", "optimum", "crosscheck")
STUDY_PACKAGES = ("scenarios.studies", "scenarios.studies.paper", "scenarios.studies.ladder",
                  "scenarios.studies.maps", "scenarios.bench")  # where the studies live
SAFE_WORD = re.compile(r"[A-Za-z0-9_.,=:+;@%-]+(/[A-Za-z0-9_.,=:+;@%-]+)*")


def argv_of(command: str, source: str = "an artifact") -> list[str]:
    """The argv ``rnhql report --refresh`` runs for an artifact's ``command``, built by this
    tool, never the text itself: the command must be a study entry point of this package
    (``rnhql aliasing|optimum|crosscheck ...`` or ``python -m PACKAGE.NAME ...``, PACKAGE one of
    :data:`STUDY_PACKAGES` and NAME a module that exists), run with this interpreter, no
    shell, and its arguments plain words and relative paths inside the checkout (no ``..``,
    no absolute path). An artifact
    is data: a JSON file that names anything else is refused (ValueError naming it)."""
    words = shlex.split(command)

    def refuse(why: str) -> ValueError:
        return ValueError(f"{source}: its command {command!r} {why}; re-run the study by hand "
                          "if you trust it")

    if not words:
        raise refuse("is empty")
    if words[0] == "rnhql" and len(words) > 1 and words[1] in ARTIFACT_SUBCOMMANDS:
        head, args = [sys.executable, "-m", "scenarios.cli", words[1]], words[2:]
    elif words[0] in ("python", "python3") and len(words) > 2 and words[1] == "-m":
        module = words[2]
        package, _, name = module.rpartition(".")
        if package not in STUDY_PACKAGES or not re.fullmatch(r"[a-z_][a-z0-9_]*", name) or \
                not (ROOT / Path(*package.split(".")) / f"{name}.py").is_file():
            raise refuse(f"runs {module!r}, not a study of this package")
        head, args = [sys.executable, "-m", module], words[3:]
    else:
        raise refuse("is not a study entry point of this package (rnhql aliasing, "
                     "optimum or crosscheck, python -m scenarios.studies.ROOM.* or "
                     "scenarios.bench.*)")
    for arg in args:
        if not SAFE_WORD.fullmatch(arg) or ".." in arg.split("/"):
            raise refuse(f"passes {arg!r}, not a plain word or a relative path in the "
                         "checkout")
    return [*head, *args]


def _redraw_figures(redraw) -> bool:
    """Redraw the docs' figures; say which could not be and why (False if any)."""
    done, skipped = redraw()
    for path in done:
        print(f"redrew {path.relative_to(ROOT)}")
    for fig, why in skipped:
        print(f"rnhql report: {fig} not redrawn: {why}", file=sys.stderr)
    return not skipped


def cmd_report(args: argparse.Namespace) -> int:
    require_checkout("rnhql report")  # the artifacts live in the source tree, not a wheel
    now = behaviour_digests()
    stale, damaged = [], []
    print("artifact | measured | took | state")
    for name in artifact_names():
        try:
            doc = load_artifact(name)
        except ArtifactError as exc:  # one row, the rest still listed
            print(f"{name} | — | — | DAMAGED: {exc}")
            damaged.append(name)
            continue
        parts = stale_parts(doc, now)
        state = f"STALE ({', '.join(parts)} changed)" if parts else "fresh"
        print(f"{name} | {doc['date']} at {doc['code_version']} | "
              f"{_took(doc.get('wall_s'))} | {state}")
        if parts:
            stale.append(doc)
    # lazy: the figures' studies load matplotlib (about 270 ms) at every rnhql command's start
    from scenarios.artifacts.figures import FIGURES, redraw

    print("\nfigure | drawn from | state")
    names = set(artifact_names()) - set(damaged)
    for fig in FIGURES:
        missing = [a for a in fig.artifacts if a not in names]
        stale_of = [a for a in fig.artifacts if a in names and stale_parts(load_artifact(a), now)]
        state = (f"MISSING ({', '.join(missing)})" if missing else
                 f"STALE ({', '.join(stale_of)})" if stale_of else "fresh")
        print(f"{fig.path} | {', '.join(fig.artifacts)} | {state}")
    if getattr(args, "figures", False) and not _redraw_figures(redraw):
        return 1
    unbacked = unbacked_in_docs(ROOT, RESULTS_DIR)
    if unbacked:
        print(f"\nfigures in prose that their artifact does not hold ({len(unbacked)}; render "
              "them from it, or correct the sentence):")
        for u in unbacked:
            print(f"  {u}")
    hand = legacy_tables()
    if hand:
        print(f"\ntyped by hand ({len(hand)}; re-run with --artifact and render them):")
        for page, command in hand:
            print(f"  {page}: {command}")
    if damaged:
        print(f"\n{len(damaged)} damaged: re-run the study that wrote each (its name says "
              "which), or restore the file from git", file=sys.stderr)
        return 1
    if not args.refresh:
        if stale:
            print(f"\n{len(stale)} stale; `rnhql report --refresh` re-runs them")
        return 0
    known = [d.get("wall_s") for d in stale]
    total = sum(w for w in known if w is not None)
    took = ("time unknown" if all(w is None for w in known) else
            f"about {_took(total)} measured last time"
            + (" (some unknown)" if None in known else ""))
    print(f"\nrefresh: {len(stale)} stale artifact(s), {took}")
    try:  # every command checked before any runs
        argvs = [argv_of(doc["command"], f"docs/results/{doc['name']}.json") for doc in stale]
    except ValueError as exc:
        print(f"rnhql report: {exc}", file=sys.stderr)
        return 2
    for doc, argv in zip(stale, argvs, strict=True):
        print(f"  {doc['command']}")
        if args.dry_run:
            continue
        code = subprocess.call(argv, cwd=ROOT)
        if code != 0:
            print(f"rnhql report: `{doc['command']}` exited with {code}; the pages are not "
                  "regenerated", file=sys.stderr)
            return 1
    if args.dry_run:
        return 0
    _redraw_figures(redraw)
    pages = [str(p) for p in generated_pages()]
    return subprocess.call([sys.executable, "-m", "cogapp", "-r", "-I", str(ROOT), *pages])

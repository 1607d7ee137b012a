"""``rnhql report``: which figures in the docs are stale, and a one-command refresh.

Every generated table in the README and ``docs/`` comes from an artifact in
``docs/results/`` (:mod:`scenarios.artifacts`). ``rnhql report`` lists them with when
and at which code version they were measured, what they took, and whether the code's
behaviour has changed since (stale), and the tables still typed by hand. ``--refresh``
re-runs the command of every stale artifact, one after another (each is a study that
uses every core), then redraws the figures and regenerates the pages (``cog -r``).
``--figures`` redraws every ``docs/`` figure from its artifacts (:mod:`scenarios.artifact_figures`).
``--dry-run`` says what a refresh would run and how long it took last time.
"""

from __future__ import annotations

import argparse
import shlex
import subprocess
import sys

from scenarios.artifacts import (
    ROOT,
    artifact_names,
    behaviour_digests,
    generated_pages,
    legacy_tables,
    load_artifact,
    stale_parts,
)


def _took(wall_s: float | None) -> str:
    if wall_s is None:
        return "unknown"
    return f"{wall_s / 60:.0f} min" if wall_s >= 90 else f"{wall_s:.0f} s"


def argv_of(command: str) -> list[str]:
    """An artifact's command as argv for this interpreter (``rnhql`` and ``python``)."""
    words = shlex.split(command)
    if words[0] == "rnhql":
        return [sys.executable, "-m", "scenarios.cli", *words[1:]]
    if words[0] in ("python", "python3"):
        return [sys.executable, *words[1:]]
    return words


def _redraw_figures(redraw) -> bool:
    """Redraw the docs' figures; say which could not be and why (False if any)."""
    done, skipped = redraw()
    for path in done:
        print(f"redrew {path.relative_to(ROOT)}")
    for fig, why in skipped:
        print(f"rnhql report: {fig} not redrawn: {why}", file=sys.stderr)
    return not skipped


def cmd_report(args: argparse.Namespace) -> int:
    from scenarios.artifacts import require_checkout

    require_checkout("rnhql report")  # the artifacts live in the source tree, not a wheel
    now = behaviour_digests()
    stale = []
    print("artifact | measured | took | state")
    for name in artifact_names():
        doc = load_artifact(name)
        parts = stale_parts(doc, now)
        state = f"STALE ({', '.join(parts)} changed)" if parts else "fresh"
        print(f"{name} | {doc['date']} at {doc['code_version']} | "
              f"{_took(doc.get('wall_s'))} | {state}")
        if parts:
            stale.append(doc)
    from scenarios.artifact_figures import FIGURES, redraw

    print("\nfigure | drawn from | state")
    names = set(artifact_names())
    for fig in FIGURES:
        missing = [a for a in fig.artifacts if a not in names]
        stale_of = [a for a in fig.artifacts if a in names and stale_parts(load_artifact(a), now)]
        state = (f"MISSING ({', '.join(missing)})" if missing else
                 f"STALE ({', '.join(stale_of)})" if stale_of else "fresh")
        print(f"{fig.path} | {', '.join(fig.artifacts)} | {state}")
    if getattr(args, "figures", False) and not _redraw_figures(redraw):
        return 1
    hand = legacy_tables()
    if hand:
        print(f"\ntyped by hand ({len(hand)}; re-run with --artifact and render them):")
        for page, command in hand:
            print(f"  {page}: {command}")
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
    for doc in stale:
        print(f"  {doc['command']}")
        if args.dry_run:
            continue
        code = subprocess.call(argv_of(doc["command"]), cwd=ROOT)
        if code != 0:
            print(f"rnhql report: `{doc['command']}` exited with {code}; the pages are not "
                  "regenerated", file=sys.stderr)
            return 1
    if args.dry_run:
        return 0
    _redraw_figures(redraw)
    pages = [str(p) for p in generated_pages()]
    return subprocess.call([sys.executable, "-m", "cogapp", "-r", "-I", str(ROOT), *pages])

"""Results as code: every figure in the docs comes from a committed artifact, and says so.

A study that the README or a ``docs/`` page quotes writes a small JSON artifact to
``docs/results/<name>.json`` (:func:`write_artifact`) holding what it measured and how:
the command, the date, the code version, and the *behaviour digests* of the code that
measured it. The Markdown tables are rendered from those files by code (:func:`render`),
inside Cog blocks (the ``cogapp`` package) in the Markdown::

    <!-- [[[cog from scenarios.artifacts import render; render("physics-grading.x") ]]] -->
    ... generated ...
    <!-- [[[end]]] -->

``cog -r README.md docs/*.md`` regenerates them; ``cog --check`` (run by the tests) fails
when a block differs from what its artifact renders to, so a table cannot drift from its
artifact unnoticed.

**Staleness shows itself.** The behaviour digests are hashes of the golden sweep's
records (``tests/data/golden_sweep.json``: every method in the grid, in physics at
``exact`` and at ``noisy``), one per method in each part a study can depend on: ``grid``,
``physics-exact``, ``physics-noisy``. A change that alters results must regenerate the
golden file (its test fails otherwise), which changes the digests of the methods it
touched. An artifact records the digests of the methods it measured, read as the methods its
data or command names (all of them when it names none: a physics check of fixed policies,
say); every table measured with an old digest then renders with a banner naming what
changed and the command that re-measures it, until that command is re-run. A refactor that
keeps every record leaves every table fresh, and so does a new method (no table measured
it). The study script's own code is hashed too (:func:`study_code_digest`).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import re
import subprocess
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from scenarios.artifacts import (
    growth,  # noqa: F401 (registers the growth study's table)
    heldout,  # noqa: F401 (registers the held-out tables)
    ladder,  # noqa: F401 (registers the ladder's tables)
)
from scenarios.artifacts.tables import KINDS
from sim.errors import InputError
from sim.files import atomic_write_text

ROOT = Path(__file__).resolve().parents[2]
RESULTS_DIR = ROOT / "docs" / "results"
GOLDEN = ROOT / "tests" / "data" / "golden_sweep.json"
PARTS = ("grid", "physics-exact", "physics-noisy")
FORMAT = "rnhql-artifact-1"
CODE_PATHS = ("sim", "learning", "scenarios", "pyproject.toml")  # "+dirty" if these changed


class ArtifactError(ValueError):
    """A missing or malformed artifact (its path, what is wrong, how to fix it)."""


def part_of(key: str) -> str:
    """Which behaviour part a golden record's key belongs to."""
    if "|grid|" in key:
        return "grid"
    return "physics-noisy" if "|fid=" in key else "physics-exact"


def method_of(key: str) -> str:
    """The method a golden record's key names (the field after its world and fidelity)."""
    fields = key.split("|")
    i = next(i for i, f in enumerate(fields) if f in ("grid", "physics"))
    rest = [f for f in fields[i + 1:] if not f.startswith("fid=")]
    return rest[0]


def _digest(rows: list) -> str:
    return hashlib.sha256(json.dumps(rows).encode()).hexdigest()[:12]


def behaviour_digests(golden: Path = GOLDEN) -> dict[str, dict[str, str]]:
    """Per part, 12 hex digits per method: a hash of that method's golden records in the
    part (and under ``"*"`` one of the whole part, what artifacts written before the
    per-method digests recorded). A table is stale when a method it measured changed, and
    stays fresh when a method is added."""
    records = json.loads(golden.read_text())
    out: dict[str, dict[str, str]] = {}
    for part in PARTS:
        rows = sorted((k, v) for k, v in records.items() if part_of(k) == part)
        methods = sorted({method_of(k) for k, _ in rows})
        out[part] = {"*": _digest(rows),
                     **{m: _digest([r for r in rows if method_of(r[0]) == m]) for m in methods}}
    return out


def changed_in(recorded: str | dict[str, str], now: object) -> list[str] | None:
    """What changed in one part since ``recorded``: None (nothing), [] (the part as a
    whole) or the methods whose records changed or are gone."""
    if not isinstance(now, dict):
        return []
    if isinstance(recorded, str):  # written before the per-method digests
        return None if now.get("*") == recorded else []
    methods = sorted(m for m, d in recorded.items() if now.get(m) != d)
    return methods or None


def code_version() -> str:
    """The git commit the study ran on (``+dirty`` with uncommitted changes), if known."""
    try:
        rev = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=ROOT,
                             capture_output=True, text=True, timeout=10, check=True).stdout
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--",
                                *CODE_PATHS], cwd=ROOT, capture_output=True, text=True,
                               timeout=10).stdout
        return rev.strip() + ("+dirty" if dirty.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def process_wall_s() -> float | None:
    """Seconds since this process started (Linux ``/proc``; None elsewhere): the study's
    wall time, which ``rnhql report`` quotes as what a refresh of it will take."""
    try:
        ticks = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
        uptime = float(Path("/proc/uptime").read_text().split()[0])
        return round(uptime - ticks / os.sysconf("SC_CLK_TCK"), 1)
    except (OSError, ValueError, IndexError):
        return None


def machine_load() -> dict[str, Any]:
    """Cores and the 1-minute load average when the study ended: wall times measured on a
    busy machine are longer, and the table says so."""
    try:
        load = round(os.getloadavg()[0], 2)
    except OSError:
        load = None
    return {"cores": os.cpu_count(), "load_1min": load}


def busy_note(doc: dict[str, Any]) -> str:
    """`` (machine busy: ...)`` when the study ended with more runnable work than cores."""
    kind = KINDS.get(doc["name"].split(".")[0])
    if kind is None or not kind.timed:
        return ""
    m = doc.get("machine") or {}
    load, cores = m.get("load_1min"), m.get("cores")
    if load is None or not cores or load <= cores:
        return ""
    return (f" The machine was busy (load {load:g} on {cores} cores at the end): wall times "
            "are longer than on a quiet machine.")


from scenarios.artifacts.digests import (  # noqa: E402, F401 (re-exported: their old home)
    STUDY_CODE,
    study_changed,
    study_code_digest,
    study_digest,
    study_helpers,
)


def _display_names() -> dict[str, str]:
    from learning.methods.registry import METHODS  # heavy (compiled methods): when writing

    return {cli: getattr(cls, "name", cli) for cli, cls in METHODS.items()}


def measured(recorded: dict[str, str], data: Any, command: str) -> dict[str, str]:
    """The digests of the methods an artifact measured, among ``recorded``'s: each method
    its data or command names (its CLI or display name as a whole word: ``rnh-ql`` is not
    ``rnh-ql+``). A table is stale when a method it measured changed, not when one it never
    ran did. An artifact that names no method at all (a physics check of fixed policies)
    keeps them all: any change of the part it depends on stales it."""
    text = json.dumps(data) + " " + command
    names = _display_names()

    def named(name: str) -> bool:
        return re.search(r"(?<![\w+-])" + re.escape(name) + r"(?![\w+-])", text) is not None

    kept = {m: d for m, d in recorded.items() if named(m) or named(names.get(m, m))}
    return kept or dict(recorded)


def write_artifact(name: str, command: str, depends_on: Iterable[str], data: Any,
                   directory: Path = RESULTS_DIR, study: str | Path | None = None) -> Path:
    """Write ``docs/results/<name>.json`` atomically: the study's figures and provenance
    (``study``: the study script's file, usually ``__file__``, hashed so that editing the
    study marks its tables stale too)."""
    parts = sorted(set(depends_on))
    unknown = [p for p in parts if p not in PARTS]
    if unknown:
        raise ArtifactError(f"{name}: unknown behaviour part(s) {unknown}; use {PARTS}")
    digests = behaviour_digests()
    doc = {"format": FORMAT, "name": name, "command": command,
           "date": _dt.date.today().isoformat(), "code_version": code_version(),
           "behaviour": {p: measured({m: d for m, d in digests[p].items() if m != "*"},
                                     data, command) for p in parts},
           "wall_s": process_wall_s(),
           "machine": machine_load(), "data": data}
    if study is not None:
        doc["study"] = study_digest(study)
    path = directory / f"{name}.json"
    atomic_write_text(path, json.dumps(doc, indent=1, sort_keys=False) + "\n")
    return path


ARTIFACT_NAME = re.compile(r"[a-z0-9][a-z0-9-]{0,63}")


def checkout_problem() -> str | None:
    """Why artifacts cannot be read or written here, or None: they live in the project's
    source tree (``docs/results``, the golden records in ``tests/data``), which an installed
    copy (``pip install .``) does not have."""
    if GOLDEN.is_file() and RESULTS_DIR.is_dir():
        return None
    return (f"needs the project's source tree (docs/results and tests/data beside "
            f"{ROOT / 'scenarios'}), and this is an installed copy without them")


def require_checkout(what: str) -> None:
    """One line and exit 2 (an :class:`~sim.errors.InputError`) where :func:`checkout_problem`
    says the artifacts are not here, before any work."""
    problem = checkout_problem()
    if problem is not None:
        raise InputError("command line", what, problem,
                         "run it from a clone of the repository (pip install -e . there)")


def check_artifact_target(name: str, flag: str = "--artifact") -> None:
    """An ``--artifact NAME`` checked before any work: a short lower-case word (it becomes a
    file name in docs/results and a Cog call; no path can escape that folder), in a
    source checkout."""
    if not ARTIFACT_NAME.fullmatch(name):
        raise InputError("command line", flag, f"{name!r} is not a name",
                         "use lower-case letters, digits and '-' (at most 64), e.g. seed7")
    require_checkout(flag)


def check_artifact_name(parser: Any, name: str) -> None:
    """Refuse an ``--artifact NAME`` that is not a short lower-case word (it becomes a file
    name and a Cog call), or a run outside a source checkout, before any work starts:
    argparse's usage error, exit 2."""
    if not ARTIFACT_NAME.fullmatch(name):
        parser.error(f"--artifact {name!r}: use lower-case letters, digits and '-' "
                     "(at most 64), e.g. --artifact seed7")
    problem = checkout_problem()
    if problem is not None:
        parser.error(f"--artifact {name!r}: {problem}; run it from a clone of the repository")


def load_artifact(name: str, directory: Path = RESULTS_DIR) -> dict[str, Any]:
    path = directory / f"{name}.json"
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise ArtifactError(f"{path}: missing; run the study that writes it") from None
    except (OSError, json.JSONDecodeError) as exc:
        raise ArtifactError(f"{path}: unreadable ({exc}); re-run the study") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ArtifactError(f"{path}: not an {FORMAT} file; re-run the study")
    problem = _malformed(doc)
    if problem is not None:
        raise ArtifactError(f"{path}: {problem}; re-run the study")
    return doc


def _malformed(doc: dict[str, Any]) -> str | None:
    """What is wrong with an artifact's provenance fields (None: nothing)."""
    for key in ("name", "command", "date", "code_version"):
        if not isinstance(doc.get(key), str):
            return f"field {key!r} is {doc.get(key)!r}, not text"
    behaviour = doc.get("behaviour")
    if not isinstance(behaviour, dict) or not all(
            isinstance(v, str | dict) for v in behaviour.values()):
        return f"field 'behaviour' is {behaviour!r}, not the behaviour digests"
    wall = doc.get("wall_s")
    if wall is not None and (isinstance(wall, bool) or not isinstance(wall, int | float)
                             or not 0 <= wall < 1e8):  # (three years: not a study's time)
        return f"field 'wall_s' is {wall!r}, not a number of seconds a study took"
    study = doc.get("study")
    if study is not None and not (isinstance(study, dict) and isinstance(study.get("path"), str)
                                  and isinstance(study.get("with", {}), dict)):
        return f"field 'study' is {study!r}, not a study's path and hash"
    if "data" not in doc:
        return "field 'data' is missing"
    return None


def stale_parts(doc: dict[str, Any], now: dict[str, str] | None = None) -> list[str]:
    """The parts whose behaviour changed since the artifact was measured, and the study's
    own script when its text changed (artifacts that recorded it)."""
    now = now or behaviour_digests()
    stale = []
    for part, recorded in sorted(doc["behaviour"].items()):
        methods = changed_in(recorded, now.get(part))
        if methods is not None:
            stale.append(f"{part} ({', '.join(methods)})" if methods else part)
    study = doc.get("study")
    if study is not None:
        if study_changed(study):
            stale.append(f"the study {study['path']}")
    return stale


def provenance(doc: dict[str, Any], now: dict[str, str] | None = None) -> str:
    """The line under a generated table, and the stale banner above it when due."""
    stale = stale_parts(doc, now)
    line = (f"<sub>Generated from `docs/results/{doc['name']}.json`, written by "
            f"`{doc['command']}` on {doc['date']} at {doc['code_version']}."
            f"{busy_note(doc)}</sub>")
    if not stale:
        return line
    return (f"> **Stale**: the code's behaviour ({', '.join(stale)}) changed since these "
            f"figures were measured; re-run `{doc['command']}`, then `cog -r` the page.\n\n"
            + line)


def rendered(name: str) -> str:
    """The Markdown of artifact ``name``: its table, then its provenance (and staleness)."""
    doc = load_artifact(name)
    kind = KINDS.get(doc["name"].split(".")[0])
    if kind is None:
        raise ArtifactError(f"no renderer for artifact {name!r}")
    stale = stale_parts(doc)
    body = kind.render(doc["data"]).rstrip("\n")
    head = provenance(doc).split("\n\n")[0] + "\n\n" if stale else ""
    tail = provenance(doc).split("\n\n")[-1]
    return f"{head}{body}\n\n{tail}\n"


def rendered_rows(names: Iterable[str]) -> str:
    """One table with a row per artifact (all of one kind, e.g. aliasing at three
    fidelities), then each artifact's provenance; a stale one's banner above the table."""
    docs = [load_artifact(n) for n in names]
    kinds = {d["name"].split(".")[0] for d in docs}
    rows = KINDS[next(iter(kinds))].render_rows if len(kinds) == 1 and \
        next(iter(kinds)) in KINDS else None
    if rows is None:
        raise ArtifactError(f"{list(names)}: give artifacts of one kind with a row renderer")
    now = behaviour_digests()
    body = rows([d["data"] for d in docs]).rstrip("\n")
    heads = [provenance(d, now).split("\n\n")[0] for d in docs if stale_parts(d, now)]
    tails = [provenance(d, now).split("\n\n")[-1] for d in docs]
    return "".join(h + "\n\n" for h in heads) + body + "\n\n" + "\n\n".join(tails) + "\n"


def cog_out(text: str) -> None:
    """Write ``text`` into the page where the running Cog block stands. Cog provides the
    ``cog`` module only while it runs a page's blocks (``cog -r README.md docs/*.md``, and
    ``cog --check`` in the tests), so it is imported here, when a block writes."""
    import cog  # exists only inside a Cog run

    cog.out(text)


def render_rows(names: list[str]) -> None:
    """For Cog blocks: :func:`rendered_rows`."""
    cog_out(rendered_rows(names))


def render(name: str) -> None:
    """For Cog blocks: write artifact ``name``'s Markdown into the page."""
    cog_out(rendered(name))


def render_text(name: str, text: Any) -> None:
    """For a Cog block: ``text(data)`` of artifact ``name`` (a sentence), then the
    artifact's provenance, as :func:`render` gives a table's."""
    doc = load_artifact(name)
    parts = provenance(doc).split("\n\n")
    head = parts[0] + "\n\n" if stale_parts(doc) else ""
    cog_out(f"{head}{text(doc['data']).rstrip()}\n\n{parts[-1]}\n")


def render_text_rows(names: list[str], text: Any) -> None:
    """For a Cog block: ``text([data, ...])`` of several artifacts (a sentence over them),
    a stale one's banner above it; their provenance is the table's above it."""
    docs = [load_artifact(n) for n in names]
    now = behaviour_digests()
    heads = [provenance(d, now).split("\n\n")[0] + "\n\n" for d in docs if stale_parts(d, now)]
    cog_out("".join(heads) + text([d["data"] for d in docs]).rstrip() + "\n")


def render_wall(name: str, what: str) -> None:
    """For a Cog block: how long the study behind artifact ``name`` took (its ``wall_s``, the
    machine's cores and load), in a sentence starting with ``what``."""
    doc = load_artifact(name)
    wall, m = doc.get("wall_s"), doc.get("machine") or {}
    took = "an unknown time" if wall is None else (f"{wall:,.0f} s ({wall / 60:.1f} min)")
    cores = m.get("cores")
    cog_out(f"{what} took {took}" + (f" on {cores} cores" if cores else "")
            + f" (`{doc['command']}`, {doc['date']}, at {doc['code_version']})."
            + busy_note(doc) + "\n")


def legacy_note(command: str, known: str = "") -> str:
    """The banner above a table typed by hand before tables were generated: its figures are
    unverified until the study is re-run with ``--artifact`` and the table replaced."""
    extra = f" Known since: {known}" if known else ""
    return (f"> **Typed by hand, not generated from an artifact**: from an earlier run of "
            f"`{command}`; unverified against today's code until that study writes an "
            f"artifact and this table is rendered from it.{extra}\n")


def legacy(command: str, known: str = "") -> None:
    """For a Cog block above a hand-typed table (see :func:`legacy_note`)."""
    cog_out(legacy_note(command, known))


LEGACY_CALL = re.compile(r'legacy\("([^"]+)"')


def artifact_names(directory: Path = RESULTS_DIR) -> list[str]:
    return sorted(p.stem for p in directory.glob("*.json"))


def generated_pages(root: Path = ROOT) -> list[Path]:
    """README.md and the docs/ pages that hold Cog blocks."""
    pages = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
    return [p for p in pages if p.exists() and "[[[cog" in p.read_text(encoding="utf-8")]


def legacy_tables(root: Path = ROOT) -> list[tuple[str, str]]:
    """(page, command) of every table still typed by hand (a ``legacy(...)`` block)."""
    return [(str(p.relative_to(root)), m.group(1)) for p in generated_pages(root)
            for m in LEGACY_CALL.finditer(p.read_text(encoding="utf-8"))]

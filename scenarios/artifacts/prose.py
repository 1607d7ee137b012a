"""Figures in prose held to the artifact the prose names.

Tables are rendered from artifacts (Cog blocks) and cannot drift; sentences can. A
sentence of the docs that names an artifact (``docs/results/<name>.json``, or
``<name>.json``), or a row of a table typed by hand that names one, is claiming its
figures come from it, so every number written there, outside code spans and Cog blocks,
must be a value the artifact holds: a number
in its data, its command or its text, equal to the written figure at the written precision
(``0.74`` matches 0.7391; ``67 %`` matches 0.67; ``1,035,415`` matches 1035415.2).

What it cannot see: a figure in a sentence that names no artifact, or one that happens to
equal some other value in the artifact. It finds the drift this project has had (a
sentence quoting a figure that an artifact re-run has changed), not every possible one.
Fractions such as ``9/10`` and numbers inside names (``paper-50``, ``512²``, ``seed7``) are
not figures here.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

# a figure: 1,035,415 or 0.74 or 60, not inside a word, a name, a path, a fraction or 512²
FIGURE = re.compile(r"(?<![\w./#@^−-])(\d{1,3}(?:,\d{3})+|\d+(?:\.\d+)?)(?![\w²/^]|\.\d|-\w)")
CODE_SPAN = re.compile(r"`[^`]*`")
LINK_TARGET = re.compile(r"\]\([^)]*\)")
NUMBER_IN_TEXT = re.compile(r"-?\d[\d,]*(?:\.\d+)?(?:[eE][+-]?\d+)?")


@dataclass(frozen=True)
class Unbacked:
    """A figure written in a sentence (or table row) that names artifacts none of which
    holds it."""

    page: str
    line: int  # 1-based, the first line of the sentence's paragraph (or the row)
    figure: str
    artifacts: tuple[str, ...]

    def __str__(self) -> str:
        return (f"{self.page}:{self.line}: {self.figure} is in none of "
                f"{', '.join(a + '.json' for a in self.artifacts)}")


def artifact_values(doc: Any) -> list[float]:
    """Every number an artifact holds: its numeric leaves, and the numbers written in its
    strings and keys (its command, rendered cells)."""
    out: list[float] = []

    def text(s: str) -> None:
        for m in NUMBER_IN_TEXT.finditer(s):
            try:
                out.append(float(m.group().replace(",", "")))
            except ValueError:
                pass

    def walk(x: Any) -> None:
        if isinstance(x, dict):
            for k, v in x.items():
                text(str(k))
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)
        elif isinstance(x, bool) or x is None:
            return
        elif isinstance(x, int | float):
            out.append(float(x))
        elif isinstance(x, str):
            text(x)

    walk(doc)
    return out


def holds(figure: str, values: list[float]) -> bool:
    """Whether ``figure`` (as written) is one of ``values`` at its precision, or one of them
    as a percentage."""
    x = float(figure.replace(",", ""))
    decimals = len(figure.split(".", 1)[1]) if "." in figure else 0
    tol = 0.5 * 10.0 ** -decimals + 1e-9
    return any(abs(v - x) <= tol or abs(100.0 * v - x) <= tol for v in values)


SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=[A-Z*(\[`])")


def claims(text: str) -> list[tuple[int, str]]:
    """(first line, text) of each unit a figure is judged in: the sentences of each prose
    paragraph (blank lines, headings, list items and ``<sub>`` provenance lines split
    paragraphs) and each table row; Cog blocks (generated) are left out."""
    out: list[tuple[int, str]] = []
    cur: list[str] = []
    first = 0
    in_cog = in_code = False

    def flush() -> None:
        if cur:
            out.extend((first, sentence) for sentence in SENTENCE_END.split(" ".join(cur)))
            cur.clear()

    for i, line in enumerate(text.splitlines(), start=1):
        stripped = line.lstrip()
        if "[[[cog" in line:
            in_cog = True
        if stripped.startswith("```"):
            in_code = not in_code
            flush()
            continue
        if in_cog or in_code or not stripped or stripped.startswith(("#", "<sub>")):
            flush()
            if "[[[end]]]" in line:
                in_cog = False
            continue
        if stripped.startswith("|"):  # a table row typed by hand: a unit of its own
            flush()
            out.append((i, line))
            continue
        if stripped.startswith(("- ", "* ")) or re.match(r"\s*\d+\. ", line):
            flush()
        if not cur:
            first = i
        cur.append(line)
    flush()
    return out


def unbacked_figures(page: str, text: str, artifacts: dict[str, Any]) -> list[Unbacked]:
    """The figures of ``text`` (a Markdown page) that the artifacts their sentence or row
    names do not hold. ``artifacts``: name (``ladder.study``) -> its JSON document."""
    values = {name: artifact_values(doc) for name, doc in artifacts.items()}
    found: list[Unbacked] = []
    for line, para in claims(text):
        named = tuple(n for n in artifacts if f"{n}.json" in para)
        if not named:
            continue
        pool = [v for n in named for v in values[n]]
        body = LINK_TARGET.sub("]", CODE_SPAN.sub(" ", para))
        for fig in FIGURE.findall(body):
            if not holds(fig, pool):
                found.append(Unbacked(page, line, fig, named))
    return found


def docs_pages(root: Path) -> list[Path]:
    """The pages whose prose may quote artifacts: README, BENCHMARKS and docs/."""
    pages = [root / "README.md", root / "BENCHMARKS.md", *sorted((root / "docs").glob("*.md"))]
    return [p for p in pages if p.exists()]


def unbacked_in_docs(root: Path, results: Path) -> list[Unbacked]:
    """Every unbacked figure in the docs under ``root`` against the artifacts in
    ``results``."""
    artifacts = {p.stem: json.loads(p.read_text(encoding="utf-8"))
                 for p in sorted(results.glob("*.json"))}
    return [u for p in docs_pages(root)
            for u in unbacked_figures(str(p.relative_to(root)), p.read_text(encoding="utf-8"),
                                      artifacts)]

"""Every relative link in README.md, BENCHMARKS.md and the docs/ pages resolves: the file
exists, and a ``#section`` anchor into a Markdown page names one of its headings.

Moving text between the README and docs/ changes what a relative path is relative to
(an image is ``docs/x.png`` from the README and ``x.png`` from a docs page); a link
that points nowhere is found here, not by a reader.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import REPO

PAGES = [REPO / "README.md", REPO / "BENCHMARKS.md", *sorted((REPO / "docs").glob("*.md"))]
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def prose(text: str) -> str:
    """The page without fenced blocks and inline code, where brackets are not links."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    return re.sub(r"`[^`\n]*`", "", text)


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`|\*|_(?=\W)|(?<=\W)_", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    found: set[str] = set()
    seen: dict[str, int] = {}
    for line in re.sub(r"^```.*?^```", "", page.read_text(encoding="utf-8"),
                       flags=re.S | re.M).splitlines():
        m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            base = slug(m.group(1))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
    return found


def links(page: Path) -> list[str]:
    return LINK.findall(prose(page.read_text(encoding="utf-8")))


def relative_links() -> list[tuple[str, str]]:
    out = []
    for page in PAGES:
        for target in links(page):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):  # https:, mailto:, ...
                continue
            out.append((page.relative_to(REPO).as_posix(), target))
    return list(dict.fromkeys(out))


LINKS = relative_links()


def test_the_pages_have_relative_links():
    assert len(LINKS) >= 10
    assert {page for page, _ in LINKS} > {"README.md"}


def test_the_link_pattern_reads_links_and_images():
    text = "see [a](x.md#b), ![img](docs/y.png) and `[not](z.md)` or [[x]](w.md)"
    assert LINK.findall(prose(text)) == ["x.md#b", "docs/y.png", "w.md"]
    assert slug("`results.json`") == "resultsjson"
    assert slug("What the paper's method does here, honestly") == (
        "what-the-papers-method-does-here-honestly")


@pytest.mark.parametrize(("page", "target"), LINKS, ids=[f"{p}: {t}" for p, t in LINKS])
def test_relative_link_resolves(page, target):
    path, _, anchor = target.partition("#")
    source = REPO / page
    resolved = (source.parent / path).resolve() if path else source
    assert resolved.exists(), f"{page}: link to {target}: {resolved} does not exist"
    assert resolved.is_relative_to(REPO), f"{page}: link to {target} leaves the repository"
    if anchor and resolved.suffix == ".md":
        assert anchor in anchors(resolved), (
            f"{page}: link to {target}: no heading with anchor #{anchor} in {path or page}")

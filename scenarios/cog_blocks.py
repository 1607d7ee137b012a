"""Writing into a docs page from a Cog block.

Cog provides the ``cog`` module only while it runs a page's blocks (``cog -r README.md
docs/*.md``, and ``cog --check`` in the tests), so it is imported here, when a block
writes, and nowhere else.
"""

from __future__ import annotations


def cog_out(text: str) -> None:
    """Write ``text`` into the page where the running Cog block stands."""
    import cog  # exists only inside a Cog run

    cog.out(text)

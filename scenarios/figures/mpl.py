"""pyplot on the file backend, loaded when a figure is drawn and not before.

matplotlib costs about 270 ms at import. The figure modules are imported by commands and
Cog blocks that draw nothing (``rnhql route`` without ``--png``, ``rnhql report``, the
docs' tables), so each drawing function asks for pyplot here, the one import of it that
waits for a figure.
"""

from __future__ import annotations

from types import ModuleType


def pyplot() -> ModuleType:
    """``matplotlib.pyplot`` with the Agg backend (files only, no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt

"""Writing a figure atomically (:func:`sim.files.atomic_path`).

A full disk or a killed process must never leave half a PNG under the real name; the
error names the file the user asked for, not the temp file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sim.files import atomic_path


def save_figure(fig: Any, path: str | Path, **kwargs: Any) -> Path:
    """``fig.savefig(path)``, atomically. The format comes from ``path``'s suffix."""
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=path.suffix.lstrip(".") or "png", **kwargs)
    return path

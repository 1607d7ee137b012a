"""Drop numba's on-disk cache of ``sim/physics`` when any of its sources changed.

numba keys a cached function on its own file's timestamp only; the primitive kernel
(:mod:`sim.physics.kernel`) inlines the sweep (:mod:`sim.physics.sweep`), so after an
edit of one the cached other would silently run old code. On import of the package the
sources are hashed and, if the hash differs from the stamp in ``__pycache__``, the
package's ``.nbi``/``.nbc`` files are deleted (numba recompiles on demand). The same
mechanism as :mod:`learning.jitcache` (``sim`` may not import ``learning``).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from sim.files import atomic_write_text

PACKAGE = Path(__file__).resolve().parent
STAMP = "physics-sources.sha256"


def drop_stale_cache(package: Path = PACKAGE) -> bool:
    """Delete the package's numba cache files if the sources changed; True if it did."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return False
    h = hashlib.sha256()
    for p in sorted(package.glob("*.py")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    digest = h.hexdigest()
    cache = package / "__pycache__"
    stamp = cache / STAMP
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for f in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
            f.unlink(missing_ok=True)
        atomic_write_text(stamp, digest)
    except OSError:  # read-only install: numba falls back to its own cache locations
        return False
    return True


def kernels_cached(package: Path = PACKAGE) -> bool:
    """Whether numba has this package's primitive kernel on disk (False on a first run, or
    after the sources changed): the commands then say compilation is under way."""
    root = os.environ.get("NUMBA_CACHE_DIR")
    dirs = (list(Path(root).glob(f"{package.name}_*")) if root
            else [package / "__pycache__"])
    return any(any(d.glob("kernel.*.nbi")) for d in dirs if d.is_dir())

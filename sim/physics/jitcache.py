"""Drop numba's on-disk cache of ``sim/physics`` when any of its sources changed.

numba keys a cached function on its own file's timestamp only; the primitive kernel
(:mod:`sim.physics.kernel.primitive`) inlines the sweep (:mod:`sim.physics.kernel.sweep`),
so after an edit of one the cached other would silently run old code. On import of the
package every source (subpackages included) is hashed and, if the hash differs from the
stamp in ``__pycache__``, the package's ``.nbi``/``.nbc`` files are deleted (numba
recompiles on demand).

The same mechanism as :mod:`learning.jitcache`, function for function: ``sim``
may not import ``learning`` nor the other way round, so the two copies are held equal by
``tests/test_learning_jitcache.py`` instead.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
STAMP = "physics-sources.sha256"
KERNELS = Path("kernel") / "primitive.py"  # the module whose cache says "compiled before"


def sources_digest(package: Path = PACKAGE) -> str:
    h = hashlib.sha256()
    for p in sorted(package.rglob("*.py")):
        h.update(str(p.relative_to(package)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def drop_stale_cache(package: Path = PACKAGE) -> bool:
    """Delete the package's numba cache files (subpackages included) if the sources
    changed; True if it did."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return False
    return restamp(package / "__pycache__", STAMP, sources_digest(package),
                   lambda: [*package.rglob("__pycache__/*.nbi"),
                            *package.rglob("__pycache__/*.nbc")])


def restamp(cache: Path, stamp_name: str, digest: str, cached) -> bool:
    """If ``cache/stamp_name`` does not hold ``digest``: delete the files ``cached()`` lists
    (numba recompiles on demand) and write the stamp atomically; True if it did. A
    read-only install keeps what it has (numba falls back to its own cache locations)."""
    stamp = cache / stamp_name
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for f in cached():
            f.unlink(missing_ok=True)
        tmp = cache / f".{stamp_name}.{os.getpid()}"
        tmp.write_text(digest)
        os.replace(tmp, stamp)
    except OSError:
        return False
    return True


def kernel_cache_dirs(package: Path = PACKAGE) -> list[Path]:
    """Where numba keeps the compiled kernels of ``package``, as it decides: the folder it
    names under ``NUMBA_CACHE_DIR`` (``<folder>_<sha1 of the folder's path>``, numba's
    own naming), or, when that cannot be created or written (or is unset), the kernel
    module's ``__pycache__``."""
    from numba.core.caching import _CacheLocator

    kernels = package / KERNELS
    root = os.environ.get("NUMBA_CACHE_DIR")
    if root:
        user = Path(root) / _CacheLocator.get_suitable_cache_subpath(str(kernels))
        if _writable(user):
            return [user]
    return [kernels.parent / "__pycache__"]


def _writable(path: Path) -> bool:
    """Whether ``path`` is, or could be created as, a folder this process writes to."""
    p = path
    while not p.exists() and p != p.parent:
        p = p.parent
    return p.is_dir() and os.access(p, os.W_OK | os.X_OK)


def kernels_cached(package: Path = PACKAGE) -> bool:
    """Whether numba has compiled kernels of this package on disk (False on a first run,
    or after the sources changed): the CLI then says compilation is under way. Every place
    numba may have put them counts (a glob over ``NUMBA_CACHE_DIR`` alone missed the
    fallback, and the notice then printed on every run)."""
    return any(any(d.glob(f"{KERNELS.stem}.*.nbi")) for d in kernel_cache_dirs(package))

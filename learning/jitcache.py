"""Drop numba's on-disk cache of this package when any of its sources changed.

numba keys a cached function on its own file's timestamp only. The kernels
inline rules from other modules, so after an edit of, say, ``rules.py`` the
cached kernels in ``compiled/kernels.py`` would silently run the old rule. On import,
:func:`drop_stale_cache` hashes every ``.py`` file of the package (subpackages
included) and, if the hash differs from the one stamped in ``__pycache__``, deletes
the package's ``.nbi``/``.nbc`` files (numba recompiles on demand). With
``NUMBA_CACHE_DIR`` set the cache lives elsewhere and is left alone (use a fresh
directory per source version).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
STAMP = "learning-sources.sha256"
KERNELS = Path("compiled") / "kernels.py"  # the module whose cache says "compiled before"
OPT_LEVEL = "2"  # LLVM's, for the kernels compiled after `import learning`


def prefer_quick_compile() -> None:
    """Compile at LLVM -O2 unless ``NUMBA_OPT`` is set: as fast as -O3 on every kernel of
    ``rnhql bench`` (within its run-to-run noise) for ~27 % less compilation on a cold
    cache (rnh-ql+: 45 -> 33 s; see BENCHMARKS.md). numba re-reads its environment at
    each compilation, so this holds for every kernel compiled from now on."""
    os.environ.setdefault("NUMBA_OPT", OPT_LEVEL)


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


# ---------------------------------------------------------------- methods from outside

# State classes of methods registered from outside this package (learning.methods.registry.register)
FOREIGN_STATES: set[type] = set()
_GUARDED = "_rnhql_foreign_guard"


def mentions(ty: object, classes: set[type], depth: int = 0) -> bool:
    """Whether the numba type ``ty`` is, or holds, a named tuple of one of ``classes``
    (through tuples, named tuples and struct references such as the state box)."""
    if getattr(ty, "instance_class", None) in classes:
        return True
    if depth > 8:
        return False
    inner = getattr(ty, "types", None)
    subs = list(inner) if isinstance(inner, tuple | list) else []
    fields = getattr(ty, "field_dict", None)
    if isinstance(fields, dict):
        subs += list(fields.values())
    return any(mentions(t, classes, depth + 1) for t in subs)


def guard_cache() -> None:
    """Keep kernels compiled for :data:`FOREIGN_STATES` out of numba's on-disk cache.

    numba's cache index of a function pickles the types of every signature it holds. A
    kernel compiled for a state class from a user's module would put that class in the
    index of, say, :mod:`learning.compiled.kernels`, and every later process that reads the index
    (any ``rnhql`` command, without the user's module on its path) would fail to import
    it. Such kernels are compiled afresh in each process instead; the package's own stay
    cached. Installed once, when the first such method is registered."""
    from numba.core import caching

    save = caching.Cache.save_overload
    if getattr(save, _GUARDED, False):
        return

    def save_overload(self, sig, data):
        if FOREIGN_STATES and any(mentions(t, FOREIGN_STATES) for t in sig):
            return None
        return save(self, sig, data)

    setattr(save_overload, _GUARDED, True)
    caching.Cache.save_overload = save_overload

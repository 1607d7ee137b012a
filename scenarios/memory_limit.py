"""The address-space limit (``ulimit -v``) read before anything heavy loads.

Why: under a small limit the command did not fail, it misbehaved. Measured on Linux
(paper-40 and a 512² map, ``rnh-ql+``): below about 400 MB numba's compiler cannot even be
loaded and llvmlite says "could not find libllvmlite.so" (it is there); at 600 MB
OpenBLAS's threads, started by numpy's import, spin at 100 % CPU for minutes and ignore
Ctrl-C and SIGTERM (one BLAS thread runs the same command in 2 s); a recording needs
between 2.4 and 4 GB, as Rerun's recorder reserves address space for its threads, and
below that it aborts in Rust or cannot start its thread. So, with a limit set: BLAS runs
one thread (nothing in rnhql is BLAS-bound), a limit below :data:`MIN_BYTES` is one line
before any import, and a recording below :data:`RECORDING_BYTES` is refused before any
training. No limit (the usual case): nothing changes.

Imports nothing heavy: the command calls :func:`prepare` before numpy is loaded.
"""

from __future__ import annotations

import os

MiB = 1024 * 1024
MIN_BYTES = 1024 * MiB  # a cold compile of the grid kernels (600 MB: LLVM aborted)
RECORDING_BYTES = 4096 * MiB  # Rerun's recorder (2.4 GB could not start its thread)
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def address_space_limit() -> int | None:
    """The soft ``RLIMIT_AS`` in bytes, or None when there is none (or no such limit on
    this system)."""
    try:
        import resource
    except ImportError:  # not POSIX
        return None
    soft, _hard = resource.getrlimit(resource.RLIMIT_AS)
    return None if soft == resource.RLIM_INFINITY else int(soft)


def _mb(n: int) -> str:
    return f"{n / MiB:,.0f} MB"


def prepare() -> str | None:
    """Before numpy loads: under a limit, one BLAS thread (unless the user chose a count);
    the one-line error when the limit is below what the command needs, else None."""
    limit = address_space_limit()
    if limit is None:
        return None
    for name in BLAS_THREADS:
        os.environ.setdefault(name, "1")
    if limit < MIN_BYTES:
        return (f"rnhql: error: ulimit -v: the address-space limit is {_mb(limit)}, below the "
                f"{_mb(MIN_BYTES)} rnhql needs to compile its kernels. Fix: raise it "
                f"(ulimit -v {MIN_BYTES // 1024}) or remove it (ulimit -v unlimited)")
    # the BLAS libraries now, while the address space is free: loaded later (numba loads
    # SciPy's at its first compile, after LLVM has taken its share) OpenBLAS's buffers
    # did not fit and its import spun for minutes
    import numpy  # noqa: F401

    try:
        import scipy.linalg  # noqa: F401  (numba's np.linalg support loads it)
    except ImportError:  # not installed: numba then has no BLAS of SciPy's to load
        pass
    return None


def recording_refused() -> tuple[str, str] | None:
    """(problem, fix) when a recording cannot be written under the address-space limit,
    else None: checked before any training, so the run is not lost to Rerun's abort."""
    limit = address_space_limit()
    if limit is None or limit >= RECORDING_BYTES:
        return None
    return (f"the address-space limit (ulimit -v) is {_mb(limit)}; Rerun's recorder needs "
            f"about {_mb(RECORDING_BYTES)} and aborts below it",
            f"raise it (ulimit -v {RECORDING_BYTES // 1024}) or remove it, or run without "
            "recording")

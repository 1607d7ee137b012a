"""One field of a checkpoint ``.npz``, read and checked before it is used: its ``.npy``
header (shape and size against a limit and the file, before anything is allocated), its
presence, the generator states, and the metrics so far. Every check raises
:class:`CheckpointError` naming the file, the field and the fix.

:mod:`learning.drivers.checkpoint` reads and writes whole checkpoints with these.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from learning.config import MAX_MAGNITUDE

METRIC_FIELDS = ("steps", "success", "returns", "wall_time_s", "shaping_mean", "shaping_std",
                 "test_episodes", "test_route_length")

# the largest array a checkpoint may hold, read from its .npy header before it is read: a
# 4096 x 4096 arena's Q-table is 0.5 GiB, RNH-QL's dense features on it 13 GiB at k = 10
MAX_ARRAY_BYTES = 16 * 1024**3
# per-episode metrics (one value per episode trained) and per-test ones (one per test)
EPISODE_METRICS = ("steps", "success", "returns", "wall_time_s", "shaping_mean",
                   "shaping_std")
TEST_METRICS = ("test_episodes", "test_route_length")


class CheckpointError(ValueError):
    """A checkpoint that cannot be used: unreadable, or not for this run."""



def read_header(data, name: str, path: Path) -> tuple[tuple[int, ...], np.dtype]:
    """The shape and dtype ``name``'s .npy header claims, read without reading the array:
    a claim beyond :data:`MAX_ARRAY_BYTES` or beyond the bytes the file holds is refused
    before anything is allocated."""
    from numpy.lib import format as npy

    try:
        info = data.zip.getinfo(f"{name}.npy")
        with data.zip.open(info) as f:
            version = npy.read_magic(f)
            shape, _fortran, dtype = (npy.read_array_header_1_0(f) if version == (1, 0)
                                      else npy.read_array_header_2_0(f))
    except (KeyError, ValueError, OSError, EOFError, zipfile.BadZipFile, AttributeError,
            TypeError, SyntaxError):
        raise CheckpointError(f"{path}: field {name!r} is unreadable: not an rnhql checkpoint "
                              "(corrupt, or an .npz from elsewhere); train again with "
                              "--save") from None
    size = int(np.prod(shape, dtype=object)) * dtype.itemsize
    if size > MAX_ARRAY_BYTES:
        raise CheckpointError(f"{path}: field {name!r} claims shape {shape} ({size:,} bytes), "
                              f"more than the limit of {MAX_ARRAY_BYTES:,} bytes; the file is "
                              "corrupt: train again with --save")
    if size > info.file_size:
        raise CheckpointError(f"{path}: field {name!r} claims shape {shape} ({size:,} bytes) "
                              f"but the file holds {info.file_size:,}; the file is corrupt: "
                              "train again with --save")
    return tuple(shape), dtype


def read_field(data, name: str, path: Path) -> np.ndarray:
    if name not in data.files:
        raise CheckpointError(f"{path}: field {name!r} is missing; the file is not a complete "
                              "rnhql checkpoint, delete it and train again")
    if getattr(data, "zip", None) is not None:
        read_header(data, name, path)
    try:
        return data[name]
    except (ValueError, OSError, EOFError, zipfile.BadZipFile):  # numpy's text would suggest
        # loading pickled data unsafely: advice a user must never take for a checkpoint
        raise CheckpointError(f"{path}: field {name!r} is unreadable: not an rnhql checkpoint "
                              "(corrupt, or an .npz from elsewhere); train again with "
                              "--save") from None


BIT_GENERATORS = ("PCG64", "PCG64DXSM", "MT19937", "Philox", "SFC64")  # numpy's own


def check_rng_state(state: object, fld: str, path: Path) -> None:
    """A generator state numpy accepts (checked now: a resumed run restores it only after
    the checks that name the file)."""
    name = state.get("bit_generator") if isinstance(state, dict) else None
    try:
        if name not in BIT_GENERATORS:
            raise ValueError(f"names no numpy bit generator ({name!r})")
        getattr(np.random, name)().state = state
    except (ValueError, TypeError, KeyError, OverflowError) as exc:
        raise CheckpointError(f"{path}: field {fld!r} is not a generator state ({exc}); the "
                              "file is corrupt, delete it and train again") from None


def read_metrics(data, path: Path, episodes: int) -> dict[str, np.ndarray]:
    """The metrics so far: every one of :data:`METRIC_FIELDS` or none (an agent saved from
    a physics run keeps none). A file with some missing would report figures computed
    from part of the record (a missing ``success`` read as "never"), so it is refused, as
    is one whose per-episode metrics do not cover the episodes its state has trained."""
    present = [k for k in METRIC_FIELDS if f"metric_{k}" in data.files]
    if not present:
        return {}
    missing = [k for k in METRIC_FIELDS if k not in present]
    if missing:
        raise CheckpointError(f"{path}: field 'metric_{missing[0]}' is missing while other "
                              "metrics are there; the file is incomplete: train again with "
                              "--save")
    metrics = {k: read_field(data, f"metric_{k}", path).copy() for k in METRIC_FIELDS}
    for k in EPISODE_METRICS:
        if metrics[k].shape != (episodes,):
            raise CheckpointError(f"{path}: field 'metric_{k}' has shape {metrics[k].shape} "
                                  f"but the agent has trained {episodes} episodes; the file "
                                  "is corrupt: train again with --save")
    if metrics["test_episodes"].shape != metrics["test_route_length"].shape or \
            metrics["test_episodes"].ndim != 1:
        raise CheckpointError(f"{path}: fields 'metric_test_episodes' and "
                              "'metric_test_route_length' differ in length; the file is "
                              "corrupt: train again with --save")
    for k, arr in metrics.items():
        if arr.dtype.kind == "f" and arr.size and (not np.isfinite(arr).all()
                                                   or np.abs(arr).max() > MAX_MAGNITUDE):
            raise CheckpointError(f"{path}: field 'metric_{k}' holds non-finite values or "
                                  f"values beyond {MAX_MAGNITUDE:g}; the file is corrupt: "
                                  "train again with --save")
    return metrics

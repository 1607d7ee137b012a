"""Save and restore a learner to ``.npz``: state arrays, config, generator state, metrics so far.

The state is stored by name (``state_tally.episode``, ``state_q``, ...), without
the arrays a method derives from its config and the scenario (its ``DERIVED``,
e.g. RNH-QL's dense feature matrix): loading rebuilds those from the geometry.
A field a method gained after a checkpoint was written (its ``ADDED``) loads with a
fresh agent's value when the file lacks it; the method's module says why that is
right for it.

Files are written atomically (a temporary file in the same directory, then
``os.replace``), so a crash mid-write leaves the old checkpoint intact. Loading
checks everything a resumed run relies on and raises :class:`CheckpointError`
(a ``ValueError``) naming the file, the field and the fix; the CLI prints it
and exits with status 2.
"""

from __future__ import annotations

import json
import os
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from learning.compiled.named_state import arrays, episodes_done, rebuild
from learning.config import MAX_MAGNITUDE, FieldMovedError, MethodConfig, config_problem
from learning.drivers.checkpoint_fields import (
    CheckpointError,
    check_rng_state,
    read_field,
    read_header,
    read_metrics,
)
from learning.drivers.state import init_state
from learning.geometry import Geometry
from learning.methods.registry import METHODS, config_from_fields, family_of, n_states_of

FORMAT = "rnhql-checkpoint-2"
# float state arrays that hold learned values (Q, network weights, V): finite and sane in
# magnitude, or every later update is inf or NaN. Others may hold inf by design (a move
# reading's "not seen yet") and are only checked for NaN.
VALUE_ARRAYS = frozenset({"q", "w", "v", "tally.f_sum", "tally.f_sq", "tally.f_mean",
                          "tally.f_std"})
# integer state arrays that compiled code indexes with, unchecked: each value's range, as
# (lowest, the size it indexes: "states", "pairs" (s * nA + a), "actions", or "slots"
# (the length of the array named after the colon) and "+1" for a count up to it). A
# value outside it would read or write outside an array: a segfault, or silent damage.
INDEX_RANGES: dict[str, tuple[int, str]] = {
    "model.successor": (-1, "states"), "model.seen": (-1, "pairs"),
    "model.n_seen": (0, "pairs+1"), "model.works": (0, ""), "model.fails": (0, ""),
    "free.neighbour": (-1, "states"), "free.distance": (-1, "states"),
    "free.queue": (-1, "states"), "free.goal": (0, "states"),
    "known.distance": (-1, "states"), "known.queue": (-1, "states"),
    "traces.pairs": (-1, "pairs"), "traces.n": (0, "pairs+1"),
    "pi_h": (-1, "actions"), "pending": (-1, "actions"), "z": (0, "states"),
    "sweep.pair": (-1, "pairs"), "sweep.where": (-1, "slots:sweep.pair"),
    "sweep.size": (0, "slots+1:sweep.pair"), "tally.episode": (0, ""),
    "tally.n_shaped": (0, ""),
}

_UMASK = os.umask(0)
os.umask(_UMASK)
_FILE_MODE = 0o666 & ~_UMASK  # what open() would have given the file


@dataclass(eq=False)
class Checkpoint:
    """A learner at an episode boundary, enough to continue it exactly."""

    config: MethodConfig
    state: object  # the method's named state
    rng_state: dict  # numpy bit_generator.state after the last episode (the learner's stream)
    env_steps: int = 0
    metrics: dict[str, np.ndarray] = field(default_factory=dict)  # METRIC_FIELDS so far
    path: str = "<memory>"  # where it was loaded from, for messages
    start_rng_state: dict | None = None  # the start cells' stream, when it has its own
    problem: dict | None = None  # what it was trained on: {"scenario": digest, "rewards": label}

    def check_problem(self, problem: dict) -> None:
        """Raise CheckpointError if this checkpoint was trained on another scenario or reward
        scheme than ``problem``, or does not say what it was trained on."""
        if self.problem is None:  # removed or never written: nothing says it fits this run
            raise CheckpointError(
                f"{self.path}: field 'problem' is missing: nothing records which scenario and "
                "rewards it was trained on, so it cannot be checked against this run; train "
                "again with rnhql train --save")
        for key, what, fix in (("rewards", "reward scheme", "resume with the same --rewards "
                                "or start without --resume"),
                               ("scenario", "scenario (content digest)",
                                "resume with the same scenario or start without --resume"),
                               ("layout", "scenario layout (content digest)",
                                "use it on the scenario it was trained on")):
            if key in problem and (key in self.problem or key != "layout") and \
                    self.problem.get(key) != problem[key]:
                raise CheckpointError(
                    f"{self.path}: field 'problem.{key}': trained with {what} "
                    f"{self.problem.get(key)!r}, this run has {problem[key]!r}; {fix}")

    @property
    def method(self) -> str:
        return self.config.cli

    @property
    def episodes(self) -> int:
        return episodes_done(self.state)

    @classmethod
    def of_result(cls, result, rng: np.random.Generator,
                  start_rng: np.random.Generator | None = None) -> Checkpoint:
        """From a :class:`learning.drivers.train.TrainResult` and the generators that trained it."""
        metrics = dict(result.episode_arrays())
        metrics["test_episodes"] = result.test_episodes
        metrics["test_route_length"] = result.test_route_length
        return cls(result.config, result.state, rng.bit_generator.state, result.env_steps,
                   metrics, start_rng_state=(None if start_rng is None
                                             else start_rng.bit_generator.state))

    @classmethod
    def of_agent(cls, agent) -> Checkpoint:
        """From a :class:`learning.drivers.agent.StepAgent` (between episodes)."""
        return cls(agent.cfg, agent.state, agent.rng.bit_generator.state)

    def check_compatible(self, cfg: MethodConfig, n_states: int,
                         geometry: Geometry | None = None) -> None:
        """Raise CheckpointError unless this checkpoint continues ``cfg`` on ``n_states`` states."""
        if cfg.cli != self.method:
            raise CheckpointError(f"{self.path}: field 'method' is {self.method!r} but this run "
                                  f"trains {cfg.cli!r}; resume with --method {self.method} or "
                                  "start without --resume")
        if cfg != self.config:
            diff = [k for k, v in cfg.fields().items() if self.config.fields().get(k) != v]
            raise CheckpointError(f"{self.path}: field 'config' differs in {', '.join(diff)} "
                                  f"(checkpoint {self.config}); use the checkpoint's settings "
                                  "or start without --resume")
        got = n_states_of(self.state)
        if got != n_states:
            raise CheckpointError(f"{self.path}: field 'n_states' is {got} but the scenario "
                                  f"has {n_states}; resume on the scenario the checkpoint was "
                                  "trained on or start without --resume")
        if geometry is not None:
            self.check_state(geometry)

    def check_state(self, geometry: Geometry) -> None:
        """Raise CheckpointError unless every state array has the shape a fresh agent of this
        method has on ``geometry`` and no float array holds NaN (no method ever stores one;
        infinities are legitimate, e.g. "never" in a config slot): compiled code indexes the
        arrays without bounds checks, and NaN values would be trained on or drawn."""
        fresh = dict(arrays(init_state(self.config, geometry, np.random.default_rng(0))))
        for name, got in arrays(self.state):
            want = fresh[name]
            if got.shape != want.shape:
                raise CheckpointError(
                    f"{self.path}: field 'state_{name}' has shape {got.shape}, but "
                    f"{self.method} on this scenario needs {want.shape}; the file is corrupt "
                    "or from another scenario: train again with --save")
            if got.dtype.kind == "f" and np.isnan(got).any():
                raise CheckpointError(
                    f"{self.path}: field 'state_{name}' holds NaN values; the file is "
                    "corrupt: train again with --save")
            if name in INDEX_RANGES and got.size:
                self._check_index_range(name, got, geometry, dict(arrays(self.state)))
            if got.dtype.kind == "f" and name in VALUE_ARRAYS and got.size and (
                    not np.isfinite(got).all() or np.abs(got).max() > MAX_MAGNITUDE):
                raise CheckpointError(
                    f"{self.path}: field 'state_{name}' holds infinite values or values "
                    f"beyond {MAX_MAGNITUDE:g} in magnitude, which no training produces; the "
                    "file is corrupt: train again with --save")

    def _check_index_range(self, name: str, got: np.ndarray, geometry: Geometry,
                           state: dict[str, np.ndarray]) -> None:
        lo, kind = INDEX_RANGES[name]
        hi = _index_limit(kind, geometry, state) if kind else None
        if got.dtype.kind == "b":
            return
        bad = got < lo if hi is None else (got < lo) | (got >= hi)
        if bad.any():
            where = f"{lo}..{hi - 1}" if hi is not None else f">= {lo}"
            raise CheckpointError(
                f"{self.path}: field 'state_{name}' holds {got[bad].flat[0]}, outside "
                f"{where} on this scenario; the file is corrupt: train again with --save")


def _index_limit(kind: str, geometry: Geometry, state: dict[str, np.ndarray]) -> int | None:
    """The exclusive upper end of an :data:`INDEX_RANGES` kind on ``geometry``."""
    base, _, other = kind.partition(":")
    plus = base.endswith("+1")
    base = base.removesuffix("+1")
    size = {"states": geometry.n_states, "pairs": geometry.n_states * geometry.n_actions,
            "actions": geometry.n_actions,
            "slots": int(state[other].shape[0]) if other in state else 0}.get(base)
    return None if size is None else size + int(plus)


def checkpoint_bytes(ckpt: Checkpoint) -> bytes:
    """The ``.npz`` of ``ckpt`` in memory: what :func:`save_checkpoint` writes, for a caller
    that writes files its own way (the CLI writes through devices and pipes)."""
    import io

    derived = set(getattr(family_of(ckpt.config), "DERIVED", ()))
    payload = {f"state_{k}": v for k, v in arrays(ckpt.state) if k not in derived}
    payload.update({f"metric_{k}": np.asarray(v) for k, v in ckpt.metrics.items()})
    payload["format"] = np.array(FORMAT)
    payload["method"] = np.array(ckpt.method)
    payload["config"] = np.array(json.dumps(ckpt.config.fields()))
    payload["rng_state"] = np.array(json.dumps(ckpt.rng_state))
    if ckpt.start_rng_state is not None:
        payload["start_rng_state"] = np.array(json.dumps(ckpt.start_rng_state))
    if ckpt.problem is not None:
        payload["problem"] = np.array(json.dumps(ckpt.problem))
    payload["env_steps"] = np.array(ckpt.env_steps, dtype=np.int64)
    payload["n_states"] = np.array(n_states_of(ckpt.state), dtype=np.int64)
    buf = io.BytesIO()
    np.savez(buf, **payload)
    return buf.getvalue()


def save_checkpoint(path: str | os.PathLike, ckpt: Checkpoint) -> Path:
    """Write ``ckpt`` to ``path`` atomically; returns the path. Only a regular file (or
    nothing) is replaced: a folder, device or pipe at ``path`` raises CheckpointError."""
    path = Path(path)
    if path.exists() and not path.is_file():
        raise CheckpointError(f"{path}: is not a regular file (a folder, device or pipe); "
                              "save the checkpoint to a file")
    data = checkpoint_bytes(ckpt)
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp",
                               dir=target.parent or ".")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _FILE_MODE)  # mkstemp makes 0600; give the usual mode
        os.replace(tmp, target)
    except OSError as exc:  # e.g. a full disk: name the checkpoint, not the temp file
        Path(tmp).unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _tiny_geometry() -> Geometry:
    """A 3 x 3 open arena: a template state on it has every array's dtype and rank."""
    ix, iy = np.meshgrid(np.arange(3), np.arange(3))
    coords = np.column_stack([ix.ravel(), iy.ravel()]) + 0.5
    return Geometry(coords=coords.astype(np.float64), goal=8, bounds_m=(0.0, 0.0, 3.0, 3.0),
                    n_states=9, n_actions=4)


def _state(data, cfg: MethodConfig, path: Path, geometry: Geometry | None,
           n_states: int | None = None):
    """The state stored in ``data``, checked field by field against a fresh one's dtypes and
    ranks; the derived arrays from ``geometry``. Without a geometry a method with derived
    arrays cannot be loaded: the stored fields (and ``n_states``) are checked first, so
    the error names what is wrong with the file before what is missing from the call."""
    derived = set(getattr(family_of(cfg), "DERIVED", ()))
    if derived and geometry is None:
        template = init_state(cfg, _tiny_geometry(), np.random.default_rng(0))
        rebuild(template, lambda name, want: want if name in derived
                else _stored(data, path, name, want))
        if n_states is not None and "state_q" in data.files:
            shape = read_header(data, "state_q", path)[0]
            got = int(shape[0]) if shape else -1
            if got != n_states:
                raise CheckpointError(f"{path}: field 'n_states' is {got} but the scenario "
                                      f"has {n_states}; resume on the scenario the checkpoint "
                                      "was trained on or start without --resume")
        raise CheckpointError(f"{path}: field 'state_{sorted(derived)[0]}' is rebuilt from the "
                              f"scenario for {cfg.cli}; load it with the scenario's geometry")
    fresh = init_state(cfg, geometry if geometry is not None else _tiny_geometry(),
                       np.random.default_rng(0))
    added = set(getattr(family_of(cfg), "ADDED", ()))

    def field_of(name: str, want: np.ndarray) -> np.ndarray:
        if name in derived or (name in added and f"state_{name}" not in data.files):
            return want  # rebuilt, or added after the file was written: the fresh value
        return _stored(data, path, name, want)

    return rebuild(fresh, field_of)


def _stored(data, path: Path, name: str, want: np.ndarray) -> np.ndarray:
    """The stored array ``state_<name>``, of ``want``'s dtype and rank."""
    if want.size == 0 and f"state_{name}" not in data.files:
        return want  # an empty field added after the checkpoint was written: nothing to read
    arr = read_field(data, f"state_{name}", path)
    if arr.dtype != want.dtype or arr.ndim != want.ndim:
        raise CheckpointError(f"{path}: field 'state_{name}' is {arr.dtype}[{arr.ndim}d], "
                              f"expected {want.dtype}[{want.ndim}d]; the file is corrupt, "
                              "delete it and train again")
    if want.size == 0 and arr.shape != want.shape:
        # a field this configuration keeps empty because nothing reads it (the RNH-QL+
        # ablation's RBF features without a network): a checkpoint from before stored it full
        return want
    return np.ascontiguousarray(arr).copy()


def _read(data, path: Path, method: str | None, geometry: Geometry | None,
          n_states: int | None = None):
    """Every field of an open npz, checked; raises CheckpointError naming the field."""
    fmt = str(read_field(data, "format", path))
    if fmt != FORMAT:
        raise CheckpointError(f"{path}: field 'format' is {fmt!r}, expected {FORMAT!r}; "
                              "train again with this version")
    name = str(read_field(data, "method", path))
    if name not in METHODS:
        raise CheckpointError(f"{path}: field 'method' is {name!r}, not one of "
                              f"{', '.join(METHODS)}; the file is corrupt, train again")
    if method is not None and name != method:
        raise CheckpointError(f"{path}: field 'method' is {name!r} but {method!r} was "
                              f"asked for; resume with --method {name} or start "
                              "without --resume")
    try:
        cfg = config_from_fields(name, json.loads(str(read_field(data, "config", path))))
        rng_state = json.loads(str(read_field(data, "rng_state", path)))
        start_rng_state = (json.loads(str(read_field(data, "start_rng_state", path)))
                           if "start_rng_state" in data.files else None)
        problem = (json.loads(str(read_field(data, "problem", path)))
                   if "problem" in data.files else None)
        if problem is not None and not isinstance(problem, dict):
            raise ValueError("problem is not a table")
    except RecursionError:
        raise CheckpointError(f"{path}: field 'config' or 'rng_state' is nested too deeply; "
                              "the file is corrupt, delete it and train again") from None
    except FieldMovedError as exc:  # a setting that has moved to another method since
        raise CheckpointError(f"{path}: field 'config': {exc}; this checkpoint cannot be "
                              "resumed: train that variant again with that method") from None
    except (ValueError, TypeError) as exc:
        raise CheckpointError(f"{path}: field 'config' or 'rng_state' is invalid ({exc}); "
                              "the file is corrupt, delete it and train again") from None
    for fld, st in (("rng_state", rng_state), ("start_rng_state", start_rng_state)):
        if st is not None or fld == "rng_state":
            check_rng_state(st, fld, path)
    problem_text = config_problem(cfg.fields())
    if problem_text is not None:
        raise CheckpointError(f"{path}: field 'config': {problem_text}; the file is corrupt "
                              "or edited: train again with --save")
    state = _state(data, cfg, path, geometry, n_states)
    metrics = read_metrics(data, path, episodes_done(state))
    try:
        env_steps = int(read_field(data, "env_steps", path))
    except (TypeError, ValueError):
        raise CheckpointError(f"{path}: field 'env_steps' is not a number; the file is "
                              "corrupt, delete it and train again") from None
    return cfg, state, rng_state, env_steps, metrics, start_rng_state, problem


def load_checkpoint(path: str | os.PathLike, method: str | None = None,
                    n_states: int | None = None, geometry: Geometry | None = None) -> Checkpoint:
    """Read a checkpoint; check its method and state count when given, and with
    ``geometry`` the shape and finiteness of every state array."""
    path = Path(path)
    if str(path) in ("", "."):
        raise CheckpointError("command line: the checkpoint path is empty; name a .npz file")
    if path.exists() and not path.is_file():  # a FIFO would block the open until a writer
        raise CheckpointError(f"{path}: is not a regular file (a folder, FIFO or device); "
                              "pass a checkpoint saved with rnhql train --save")
    try:
        fh = open(path, "rb")  # closed below, also when np.load fails
    except FileNotFoundError:
        raise CheckpointError(f"{path}: no such checkpoint file; check the path") from None
    except OSError as exc:
        raise CheckpointError(f"{path}: cannot be opened ({exc}); check the path and its "
                              "permissions") from None
    with fh:
        try:
            data = np.load(fh, allow_pickle=False)
        except (ValueError, OSError, EOFError, zipfile.BadZipFile):
            raise CheckpointError(f"{path}: is not an rnhql checkpoint (not a readable .npz "
                                  "of plain arrays); the file is corrupt or from elsewhere: "
                                  "check the path, or train again with --save") from None
        if not hasattr(data, "files"):
            raise CheckpointError(f"{path}: holds a single array, not an rnhql checkpoint "
                                  "(.npz); check the path")
        with data:
            cfg, state, rng_state, env_steps, metrics, start_state, problem = _read(
                data, path, method, geometry, n_states)
    ckpt = Checkpoint(cfg, state, rng_state, env_steps, metrics, str(path), start_state,
                      problem)
    if n_states is not None:
        ckpt.check_compatible(cfg, n_states, geometry)
    elif geometry is not None:
        ckpt.check_state(geometry)
    return ckpt

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

from learning.config import FieldMovedError, MethodConfig
from learning.geometry import Geometry
from learning.named_state import arrays, episodes_done, rebuild
from learning.registry import METHODS, config_from_fields, family_of, n_states_of
from learning.state import init_state

FORMAT = "rnhql-checkpoint-2"
METRIC_FIELDS = ("steps", "success", "returns", "wall_time_s", "shaping_mean", "shaping_std",
                 "test_episodes", "test_route_length")

_UMASK = os.umask(0)
os.umask(_UMASK)
_FILE_MODE = 0o666 & ~_UMASK  # what open() would have given the file


class CheckpointError(ValueError):
    """A checkpoint that cannot be used: unreadable, or not for this run."""


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
        scheme than ``problem`` (older checkpoints without the record are not checked)."""
        if self.problem is None:
            return
        for key, what, fix in (("rewards", "reward scheme", "the same --rewards"),
                               ("scenario", "scenario (content digest)", "the same scenario")):
            if key in problem and self.problem.get(key) != problem[key]:
                raise CheckpointError(
                    f"{self.path}: field 'problem.{key}': trained with {what} "
                    f"{self.problem.get(key)!r}, this run has {problem[key]!r}; resume with "
                    f"{fix} or start without --resume")

    @property
    def method(self) -> str:
        return self.config.cli

    @property
    def episodes(self) -> int:
        return episodes_done(self.state)

    @classmethod
    def of_result(cls, result, rng: np.random.Generator,
                  start_rng: np.random.Generator | None = None) -> Checkpoint:
        """From a :class:`learning.train.TrainResult` and the generators that trained it."""
        metrics = dict(result.episode_arrays())
        metrics["test_episodes"] = result.test_episodes
        metrics["test_route_length"] = result.test_route_length
        return cls(result.config, result.state, rng.bit_generator.state, result.env_steps,
                   metrics, start_rng_state=(None if start_rng is None
                                             else start_rng.bit_generator.state))

    @classmethod
    def of_agent(cls, agent) -> Checkpoint:
        """From a :class:`learning.agent.StepAgent` (between episodes)."""
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


def save_checkpoint(path: str | os.PathLike, ckpt: Checkpoint) -> Path:
    """Write ``ckpt`` to ``path`` atomically; returns the path."""
    path = Path(path)
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
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **payload)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _FILE_MODE)  # mkstemp makes 0600; give the usual mode
        os.replace(tmp, path)
    except OSError as exc:  # e.g. a full disk: name the checkpoint, not the temp file
        Path(tmp).unlink(missing_ok=True)
        raise OSError(exc.errno, exc.strerror, str(path)) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _field(data, name: str, path: Path) -> np.ndarray:
    if name not in data.files:
        raise CheckpointError(f"{path}: field {name!r} is missing; the file is not a complete "
                              "rnhql checkpoint, delete it and train again")
    try:
        return data[name]
    except (ValueError, OSError, EOFError, zipfile.BadZipFile):  # numpy's text would suggest
        # loading pickled data unsafely: advice a user must never take for a checkpoint
        raise CheckpointError(f"{path}: field {name!r} is unreadable: not an rnhql checkpoint "
                              "(corrupt, or an .npz from elsewhere); train again with "
                              "--save") from None


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
            got = int(data["state_q"].shape[0])
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
    arr = _field(data, f"state_{name}", path)
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
    fmt = str(_field(data, "format", path))
    if fmt != FORMAT:
        raise CheckpointError(f"{path}: field 'format' is {fmt!r}, expected {FORMAT!r}; "
                              "train again with this version")
    name = str(_field(data, "method", path))
    if name not in METHODS:
        raise CheckpointError(f"{path}: field 'method' is {name!r}, not one of "
                              f"{', '.join(METHODS)}; the file is corrupt, train again")
    if method is not None and name != method:
        raise CheckpointError(f"{path}: field 'method' is {name!r} but {method!r} was "
                              f"asked for; resume with --method {name} or start "
                              "without --resume")
    try:
        cfg = config_from_fields(name, json.loads(str(_field(data, "config", path))))
        rng_state = json.loads(str(_field(data, "rng_state", path)))
        start_rng_state = (json.loads(str(_field(data, "start_rng_state", path)))
                           if "start_rng_state" in data.files else None)
        problem = (json.loads(str(_field(data, "problem", path)))
                   if "problem" in data.files else None)
        if problem is not None and not isinstance(problem, dict):
            raise ValueError("problem is not a table")
    except FieldMovedError as exc:  # a setting that has moved to another method since
        raise CheckpointError(f"{path}: field 'config': {exc}; this checkpoint cannot be "
                              "resumed: train that variant again with that method") from None
    except (ValueError, TypeError) as exc:
        raise CheckpointError(f"{path}: field 'config' or 'rng_state' is invalid ({exc}); "
                              "the file is corrupt, delete it and train again") from None
    state = _state(data, cfg, path, geometry, n_states)
    metrics = {k: _field(data, f"metric_{k}", path).copy() for k in METRIC_FIELDS
               if f"metric_{k}" in data.files}
    env_steps = int(_field(data, "env_steps", path))
    return cfg, state, rng_state, env_steps, metrics, start_rng_state, problem


def load_checkpoint(path: str | os.PathLike, method: str | None = None,
                    n_states: int | None = None, geometry: Geometry | None = None) -> Checkpoint:
    """Read a checkpoint; check its method and state count when given, and with
    ``geometry`` the shape and finiteness of every state array."""
    path = Path(path)
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

"""Issue 39, the last three: the stochastic-model cache is checked like the physics-model
cache; an interrupted sweep leaves nothing that ``--resume`` cannot use; a signal ends a
pooled sweep promptly, whatever the workers were doing (the pool's end could hang).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parent.parent


# ------------------------------------------------------------------ 1: the stochastic-model cache
@pytest.fixture
def small_model(tmp_path, monkeypatch):
    """A small map's stochastic model at ``noisy`` built into an empty cache folder: (the
    model's arguments, the fresh model, its cache file)."""
    from sim.physics import stochastic_build as sb
    from sim.physics.fidelity import parse_fidelity
    from sim.physics.static import PhysicsConfig
    from sim.physics.stochastic_model import Sampling
    from sim.scenario import Circle, Scenario

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.delenv("RNHQL_NO_DISK_CACHE", raising=False)
    sc = Scenario(name="graze", width_m=6.0, height_m=6.0, start=(1, 0), goal=(1, 5),
                  obstacles=(Circle(3.448, 3.05, 1.6385),), steps_per_episode=60)
    args = (sc, parse_fidelity("noisy"),
            Sampling(samples=2, refined=4, particles=2, particle_samples=1, seed=3))
    sb.stochastic_model.cache_clear()
    fresh = sb.stochastic_model(*args)
    path = sb.cache_dir() / f"{sb.digest(sc, PhysicsConfig(), *args[1:])}.npz"
    assert path.is_file()
    yield args, fresh, path
    sb.stochastic_model.cache_clear()


MODEL_ARRAYS = ("state_cell", "state_context", "state_pose", "sa_ptr", "dst", "prob",
                "mean_steps")


def _same_model(a, b) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k), equal_nan=k == "state_pose")
               for k in MODEL_ARRAYS) and a.primitives == b.primitives


def _damage(path: Path, how: str) -> None:
    """Damage a cache file the way ``how`` says; the tampered kinds that keep the file's
    SHA-256 consistent must be caught by the model's own check."""
    from sim.physics.disk_cache import content_digest
    from sim.physics.stochastic_build import CACHE

    raw = path.read_bytes()
    if how == "truncate":
        path.write_bytes(raw[: len(raw) // 2])
        return
    if how == "junk":
        path.write_bytes(b"PK\x03\x04" + bytes(100))
        return
    if how == "folder":
        path.unlink()
        path.mkdir()
        return
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    names = CACHE.arrays
    if how == "flipped-byte":  # a probability changed, the SHA-256 left as it was
        arrays["prob"] = arrays["prob"].copy()
        arrays["prob"][0] = 0.5 * arrays["prob"][0]
    elif how == "wrong-key":
        arrays["key"] = np.array("0" * 20)
    elif how == "missing-array":
        del arrays["mean_steps"]
    else:
        if how == "dst-out-of-range":
            arrays["dst"] = arrays["dst"].copy()
            arrays["dst"][-1] = 10 ** 6  # an index the solver would read beyond its arrays
        elif how == "short-shape":
            arrays["mean_steps"] = arrays["mean_steps"][:-1]
        elif how == "other-arena":
            arrays["nx"] = np.array(int(arrays["nx"]) + 1)
        arrays["sha256"] = np.array(content_digest({k: arrays[k] for k in names}))
    with open(path, "wb") as f:
        np.savez(f, **arrays)


@pytest.mark.parametrize("how", ["truncate", "junk", "folder", "flipped-byte", "wrong-key",
                                 "missing-array", "dst-out-of-range", "short-shape",
                                 "other-arena"])
def test_a_damaged_or_tampered_stochastic_model_cache_is_rebuilt_and_said(small_model, how,
                                                                          capsys):
    from sim.physics import stochastic_build as sb

    args, fresh, path = small_model
    capsys.readouterr()
    _damage(path, how)
    sb.stochastic_model.cache_clear()
    again = sb.stochastic_model(*args)
    assert _same_model(again, fresh)  # the same seed: the same model, rebuilt
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(lines) == 1 and str(path) in lines[0] and "rebuilding" in lines[0], lines
    assert path.is_file()  # rewritten whole, and sound: used as is from now on
    sb.stochastic_model.cache_clear()
    assert _same_model(sb.stochastic_model(*args), fresh)
    assert capsys.readouterr().err == ""


def test_a_sound_stochastic_model_cache_is_used_as_is_and_quietly(small_model, monkeypatch,
                                                                  capsys):
    from sim.physics import stochastic_build as sb

    args, fresh, _ = small_model
    capsys.readouterr()
    monkeypatch.setattr(sb, "build_stochastic_model",
                        lambda *a: pytest.fail("rebuilt a sound cache"))
    sb.stochastic_model.cache_clear()
    assert _same_model(sb.stochastic_model(*args), fresh)
    assert capsys.readouterr().err == ""


def test_the_two_model_caches_share_one_mechanism():
    """One fact, one home: both caches are kinds of :mod:`sim.physics.disk_cache`, and
    neither module reads or writes an .npz of its own."""
    from sim.physics import disk_cache, model, stochastic_build

    assert {model.CACHE.folder, stochastic_build.CACHE.folder} == {"physics-graph",
                                                                   "stochastic-model"}
    for mod in (model, stochastic_build):
        assert isinstance(mod.CACHE, disk_cache.CacheKind)
        src = Path(mod.__file__).read_text()
        assert "np.load(" not in src and "np.savez" not in src and "atomic_path" not in src

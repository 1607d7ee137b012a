"""The JIT cache of learning/ is dropped when any of its sources changes."""

from __future__ import annotations

from learning.jitcache import drop_stale_cache


def test_cache_dropped_on_source_change(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    (tmp_path / "rules.py").write_text("x = 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    (cache / "kernels.f-1.py311.nbi").write_text("")
    (cache / "kernels.cpython-311.pyc").write_text("")
    assert drop_stale_cache(tmp_path)
    assert not (cache / "kernels.f-1.py311.nbi").exists()
    assert (cache / "kernels.cpython-311.pyc").exists()
    (cache / "kernels.f-1.py311.nbi").write_text("")
    assert not drop_stale_cache(tmp_path)  # unchanged sources: cache kept
    assert (cache / "kernels.f-1.py311.nbi").exists()
    (tmp_path / "rules.py").write_text("x = 2\n")
    assert drop_stale_cache(tmp_path)
    assert not (cache / "kernels.f-1.py311.nbi").exists()


def test_custom_cache_dir_left_alone(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    (tmp_path / "a.py").write_text("")
    assert not drop_stale_cache(tmp_path)


def _opt_level_after_import(env: dict[str, str]) -> str:
    import os
    import subprocess
    import sys

    code = ("import learning, numba.core.config as c; c.reload_config(); "
            "print(int(c.OPT))")
    full = {k: v for k, v in os.environ.items() if k != "NUMBA_OPT"} | env
    return subprocess.run([sys.executable, "-c", code], env=full, capture_output=True,
                          text=True, check=True).stdout.strip()


def test_kernels_compile_at_O2_unless_the_user_says_otherwise():
    assert _opt_level_after_import({}) == "2"
    assert _opt_level_after_import({"NUMBA_OPT": "3"}) == "3"


def test_kernels_cached_finds_numbas_folder_under_numba_cache_dir(tmp_path, monkeypatch):
    from learning.jitcache import kernels_cached

    pkg = tmp_path / "src" / "learning"
    pkg.mkdir(parents=True)
    root = tmp_path / "cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(root))
    assert not kernels_cached(pkg)
    from numba.core.caching import _CacheLocator

    # numba's: <folder>_<sha1 of the folder's path> (this checkout's, not any learning_*)
    folder = root / _CacheLocator.get_suitable_cache_subpath(str(pkg / "compiled" / "kernels.py"))
    folder.mkdir(parents=True)
    (folder / "kernels._episodes-22.py311.nbi").write_bytes(b"")
    assert kernels_cached(pkg)


def test_the_physics_cache_is_the_same_mechanism_function_for_function():
    """``sim`` and ``learning`` may not import each other, so each has its copy of the cache
    mechanism; they differ only in their constants (which package, which kernel module)."""
    import inspect

    import learning.jitcache as learning_cache
    import sim.physics.jitcache as physics_cache

    for name in ("sources_digest", "drop_stale_cache", "restamp", "kernel_cache_dirs",
                 "_writable", "kernels_cached"):
        assert inspect.getsource(getattr(physics_cache, name)) == \
            inspect.getsource(getattr(learning_cache, name)), name


def test_a_physics_subpackage_edit_drops_the_physics_cache(tmp_path, monkeypatch):
    from sim.physics.jitcache import drop_stale_cache as drop_physics

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    (tmp_path / "kernel").mkdir()
    (tmp_path / "kernel" / "sweep.py").write_text("x = 1\n")
    cache = tmp_path / "kernel" / "__pycache__"
    cache.mkdir()
    drop_physics(tmp_path)
    (cache / "primitive.advance-1.py311.nbi").write_text("")
    assert not drop_physics(tmp_path)
    (tmp_path / "kernel" / "sweep.py").write_text("x = 2\n")
    assert drop_physics(tmp_path)
    assert not (cache / "primitive.advance-1.py311.nbi").exists()

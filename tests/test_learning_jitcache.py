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

"""sim.files: a write either replaces the file whole or leaves it as it was, no temp file."""

from __future__ import annotations

import pytest

from sim.files import atomic_path, atomic_write_bytes, atomic_write_text


def test_a_failed_write_leaves_the_old_file_and_no_temp(tmp_path):
    path = tmp_path / "sub" / "r.json"
    atomic_write_text(path, "old")
    with pytest.raises(RuntimeError), atomic_path(path) as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed mid-write")
    assert path.read_text() == "old"
    assert sorted(p.name for p in path.parent.iterdir()) == ["r.json"]
    atomic_write_bytes(path, b"new")
    assert path.read_bytes() == b"new"
    assert sorted(p.name for p in path.parent.iterdir()) == ["r.json"]


def test_an_os_error_names_the_file_not_the_temp(tmp_path):
    path = tmp_path / "out.png"
    with pytest.raises(OSError) as err, atomic_path(path) as tmp:
        raise OSError(28, "No space left on device", str(tmp))
    assert err.value.filename == str(path) and err.value.errno == 28
    assert list(tmp_path.iterdir()) == []

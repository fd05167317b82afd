"""Atomic writes: nothing half-written, an existing file replaced only by a complete one."""

from __future__ import annotations

import pytest

from asbuilt.atomic import AtomicBatch, atomic_write
from asbuilt.errors import ExportError


def test_atomic_write_replaces_only_on_success(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_write(target, "w") as f:
            f.write("partial")
            raise RuntimeError("writer failed")
    assert target.read_text() == "old"
    assert list(tmp_path.iterdir()) == [target]
    with atomic_write(target, "w") as f:
        f.write("new")
    assert target.read_text() == "new"


def test_batch_publishes_all_or_nothing(tmp_path):
    a, b = tmp_path / "a.bin", tmp_path / "b.bin"
    with pytest.raises(RuntimeError):
        with AtomicBatch() as batch:
            batch.stage(a).write_bytes(b"a")
            raise RuntimeError("second output failed")
    assert list(tmp_path.iterdir()) == []
    with AtomicBatch() as batch:
        batch.stage(a).write_bytes(b"a")
        batch.stage(b).write_bytes(b"b")
    assert a.read_bytes() == b"a" and b.read_bytes() == b"b"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin", "b.bin"]


def test_missing_directory_is_one_clear_error(tmp_path):
    with pytest.raises(ExportError) as info:
        with atomic_write(tmp_path / "nope" / "out.step") as f:
            f.write(b"x")
    assert str(info.value).endswith("directory does not exist; create it or choose another --out")


def test_published_files_have_the_usual_permissions(tmp_path):
    from asbuilt.atomic import default_file_mode

    target = tmp_path / "out.json"
    with atomic_write(target, "w") as f:
        f.write("{}")
    assert target.stat().st_mode & 0o777 == default_file_mode()

"""Atomic writes: nothing half-written, an existing file replaced only by a complete one."""

from __future__ import annotations

import pytest

from asbuilt.atomic import AtomicBatch, atomic_write, check_target
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


def test_a_directory_target_fails_before_anything_is_written(tmp_path):
    (tmp_path / "taken.glb").mkdir()
    with pytest.raises(ExportError) as info:
        with AtomicBatch() as batch:
            batch.stage(tmp_path / "a.step").write_bytes(b"a")
            batch.stage(tmp_path / "taken.glb").write_bytes(b"b")
    assert str(info.value).startswith(f"{tmp_path / 'taken.glb'}: is a directory; give a file")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken.glb"]
    with pytest.raises(ExportError, match="is a directory"):
        with atomic_write(tmp_path / "taken.glb") as f:
            f.write(b"x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken.glb"]


def test_a_directory_target_is_told_what_kind_of_file_to_add(tmp_path):
    with pytest.raises(ExportError) as info:
        check_target(tmp_path, "--output", example="fit.json")
    assert str(info.value) == (
        f"{tmp_path}: is a directory; give a file name to write (e.g. add /fit.json)"
    )
    with pytest.raises(ExportError, match=r"\(e\.g\. add /model\.step\)$"):
        check_target(tmp_path)  # a model is the default


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("", "'': the output file name is empty; give a file name"),
        (
            "no/such/out.json",
            "no/such/out.json: directory does not exist; create it or choose another --fix",
        ),
    ],
)
def test_check_target_messages(tmp_path, monkeypatch, name, message):
    from asbuilt.atomic import check_target

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ExportError) as info:
        check_target(name, "--fix")
    assert str(info.value) == message


def test_a_symbolic_link_is_written_through(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    with atomic_write(link, "w") as f:
        f.write("new")
    assert link.is_symlink() and target.read_text() == "new"
    with AtomicBatch() as batch:
        batch.stage(link).write_text("newer")
    assert link.is_symlink() and target.read_text() == "newer"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "real.json"]


def test_a_named_pipe_gets_the_content(tmp_path):
    import os
    import threading

    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    received = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()
    with AtomicBatch() as batch:
        batch.stage(fifo).write_bytes(b"complete")
    reader.join(timeout=10)
    assert received == [b"complete"]
    assert fifo.is_fifo()  # still a pipe, not replaced by a regular file
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()
    with atomic_write(fifo, "w") as f:
        f.write("text")
    reader.join(timeout=10)
    assert received[1] == b"text" and fifo.is_fifo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe.json"]


def test_a_failed_rename_discards_what_is_not_published(tmp_path, monkeypatch):
    import os

    real_replace = os.replace
    calls = []

    def failing_replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(ExportError) as info:
        with AtomicBatch() as batch:
            for name in ("a.bin", "b.bin", "c.bin"):
                batch.stage(tmp_path / name).write_bytes(b"x")
    assert (
        str(info.value) == f"{tmp_path / 'b.bin'}: cannot write the file (No space left on device)"
    )
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".part")]


@pytest.mark.skipif(not __import__("os").path.exists("/dev/full"), reason="needs /dev/full")
def test_a_device_that_fails_at_commit_leaves_the_files_unpublished(tmp_path):
    """``--out ok.glb --out full.step`` with full.step a link to /dev/full: ok.glb was renamed
    into place before the device refused its bytes, so the failed run left one output."""
    import os

    ok, full = tmp_path / "ok.glb", tmp_path / "full.step"
    ok.write_bytes(b"old")
    os.symlink("/dev/full", full)
    with pytest.raises(ExportError) as info:
        with AtomicBatch() as batch:
            batch.stage(ok).write_bytes(b"new")
            batch.stage(full).write_bytes(b"x" * 100_000)
    assert "No space left on device" in str(info.value)
    assert ok.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["full.step", "ok.glb"]


def test_pipes_get_their_content_before_files_are_renamed(tmp_path, monkeypatch):
    import os
    import shutil
    import threading

    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    order = []
    real_replace, real_copy = os.replace, shutil.copyfileobj
    monkeypatch.setattr(os, "replace", lambda a, b: (order.append("rename"), real_replace(a, b)))
    monkeypatch.setattr(shutil, "copyfileobj", lambda a, b: (order.append("pipe"), real_copy(a, b)))
    received = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()
    with AtomicBatch() as batch:
        batch.stage(tmp_path / "a.bin").write_bytes(b"a")
        batch.stage(fifo).write_bytes(b"p")
        batch.stage(tmp_path / "b.bin").write_bytes(b"b")
    reader.join(timeout=10)
    assert order == ["pipe", "rename", "rename"] and received == [b"p"]


def test_a_batch_publishes_nothing_while_the_process_terminates(tmp_path):
    from asbuilt.atomic import TERMINATING

    TERMINATING.set()
    try:
        with pytest.raises(ExportError, match="terminated"):
            with AtomicBatch() as batch:
                batch.stage(tmp_path / "a.bin").write_bytes(b"a")
    finally:
        TERMINATING.clear()
    assert list(tmp_path.iterdir()) == []


def test_a_link_to_a_pipe_writes_into_the_pipe(tmp_path):
    # As /dev/stdout -> /proc/self/fd/1 -> pipe:[...] when the output is piped.
    import os
    import threading

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    link = tmp_path / "out.json"
    link.symlink_to(fifo)
    received = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()
    with atomic_write(link, "w") as f:
        f.write("through the link")
    reader.join(timeout=10)
    assert received == [b"through the link"]
    assert link.is_symlink() and fifo.is_fifo()


def test_a_name_ending_in_a_slash_is_refused(tmp_path, monkeypatch):
    from asbuilt.atomic import check_target

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ExportError) as info:
        check_target("newdir/")
    assert (
        str(info.value) == "newdir/: ends with a slash, so it names a directory; give a file name"
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("how", ["same name", "relative name", "symbolic link"])
def test_an_output_that_is_the_input_is_refused(tmp_path, monkeypatch, how):
    """`asbuilt check site.json --fix site.json` replaced the scan's measured points with the
    model written from them (audit): an output naming an input file is refused."""
    from asbuilt.atomic import check_target

    scan = tmp_path / "site.json"
    scan.write_text("{}")
    monkeypatch.chdir(tmp_path)
    target = {"same name": scan, "relative name": "site.json"}.get(how)
    if target is None:
        target = tmp_path / "link.json"
        target.symlink_to(scan)
    with pytest.raises(ExportError, match="is the input file itself") as err:
        check_target(target, "--fix", inputs=[str(scan)])
    assert "choose another --fix" in str(err.value)
    assert check_target(tmp_path / "other.json", "--fix", inputs=[str(scan)]).name == "other.json"


def test_a_read_only_output_is_kept_not_replaced(tmp_path, monkeypatch):
    # A rename replaces a file the directory lets us replace, whatever its own mode: a file
    # made read-only to keep it would be lost silently.
    import os

    kept = tmp_path / "kept.step"
    kept.write_text("measured")
    kept.chmod(0o444)
    if os.geteuid() == 0:  # root may write any file: be a user for os.access
        real_access = os.access
        monkeypatch.setattr(
            os, "access", lambda path, mode: mode != os.W_OK and real_access(path, mode)
        )
    with pytest.raises(ExportError, match="kept.step: is read-only; make it writable"):
        check_target(kept)
    with pytest.raises(ExportError, match="is read-only"):
        with AtomicBatch() as batch:
            batch.stage(kept).write_text("new")
    assert kept.read_text() == "measured"

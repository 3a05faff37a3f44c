"""Atomic writes: the file appears whole or not at all, with ordinary permissions."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from reform.atomic import (
    OutputPathError,
    atomic_open,
    atomic_path,
    check_file_path,
    check_folder_path,
)


def test_written_file_has_the_permissions_of_a_plain_open(tmp_path):
    mask = os.umask(0o022)
    try:
        with atomic_open(tmp_path / "out.txt") as handle:
            handle.write("hello")
    finally:
        os.umask(mask)
    mode = stat.S_IMODE((tmp_path / "out.txt").stat().st_mode)
    assert mode == 0o644
    assert (tmp_path / "out.txt").read_text() == "hello"


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError, match="interrupted"):
        with atomic_open(target) as handle:
            handle.write("half")
            raise RuntimeError("interrupted")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_atomic_path_creates_missing_folders(tmp_path):
    target = tmp_path / "a" / "b" / "c.bin"
    with atomic_path(target) as tmp:
        tmp.write_bytes(b"\x00\x01")
    assert target.read_bytes() == b"\x00\x01"


def test_atomic_open_refuses_read_modes(tmp_path):
    with pytest.raises(ValueError, match="mode must start with 'w'"):
        with atomic_open(tmp_path / "x", "r"):
            pass


@pytest.mark.parametrize("writer", ["atomic_path", "atomic_open"])
def test_an_existing_folder_is_refused_before_anything_is_written(tmp_path, writer):
    target = tmp_path / "report.json"
    target.mkdir()
    opener = atomic_path if writer == "atomic_path" else atomic_open
    with pytest.raises(
        OutputPathError, match="report.json: expected a file path, found an existing folder"
    ):
        with opener(target):
            raise AssertionError("the body must not run")
    assert target.is_dir() and list(tmp_path.iterdir()) == [target]


@pytest.mark.parametrize("below", ["out.json", "sub/out.json"])
def test_a_path_under_a_file_is_refused(tmp_path, below):
    (tmp_path / "afile").write_text("x")
    target = tmp_path / "afile" / below
    with pytest.raises(OutputPathError, match=r"expected a folder at .*afile, found a file"):
        with atomic_open(target):
            raise AssertionError("the body must not run")
    assert (tmp_path / "afile").read_text() == "x"


def test_a_folder_path_ending_in_a_slash_is_refused(tmp_path):
    with pytest.raises(
        OutputPathError, match="expected a file path, found a folder path ending in /"
    ):
        with atomic_open(f"{tmp_path}/missing/"):
            pass
    assert list(tmp_path.iterdir()) == []


def test_output_path_error_is_a_value_error_naming_the_path(tmp_path):
    error = OutputPathError(tmp_path / "x", "expected a file path, found an existing folder")
    assert isinstance(error, ValueError)
    assert str(error) == f"{tmp_path / 'x'}: expected a file path, found an existing folder"
    assert error.path == tmp_path / "x"


def test_check_file_path_writes_and_creates_nothing(tmp_path):
    target = tmp_path / "a" / "b" / "out.json"
    assert check_file_path(target) == target
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "dir").mkdir()
    with pytest.raises(OutputPathError, match="found an existing folder"):
        check_file_path(tmp_path / "dir")


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
def test_a_folder_that_cannot_be_created_is_named(tmp_path):
    with pytest.raises(OutputPathError, match=r"/proc/x/m.skops: folder /proc/x cannot be created"):
        check_file_path("/proc/x/m.skops")
    with pytest.raises(OutputPathError, match=r"/proc/x/m.skops: folder /proc/x cannot be created"):
        with atomic_path("/proc/x/m.skops"):
            raise AssertionError("the body must not run")


def test_check_folder_path(tmp_path):
    (tmp_path / "afile").write_text("x")
    assert check_folder_path(tmp_path / "new" / "dir") == tmp_path / "new" / "dir"
    assert check_folder_path(tmp_path) == tmp_path
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]
    with pytest.raises(
        OutputPathError, match="afile: expected a folder path, found an existing file"
    ):
        check_folder_path(tmp_path / "afile")
    with pytest.raises(
        OutputPathError, match=r"afile/sub: expected a folder at .*afile, found a file"
    ):
        check_folder_path(tmp_path / "afile" / "sub")


def test_write_parquet_names_an_unwritable_target(tmp_path):
    import numpy as np

    from reform import Dataset, Frame
    from reform.datasets import write_parquet

    frame = Frame(
        ids=np.array([1, 2]), position=np.zeros((2, 2)), yaw=np.zeros(2), groups=((1, 2),)
    )
    dataset = Dataset(frames=(frame,), name="tiny")
    (tmp_path / "folder.parquet").mkdir()
    (tmp_path / "afile").write_text("x")
    with pytest.raises(
        OutputPathError, match="folder.parquet: expected a file path, found an existing folder"
    ):
        write_parquet(dataset, tmp_path / "folder.parquet")
    with pytest.raises(OutputPathError, match=r"expected a folder at .*afile, found a file"):
        write_parquet(dataset, tmp_path / "afile" / "x.parquet")


def test_a_dangling_link_is_named_as_such(tmp_path):
    from reform.atomic import OutputPathError, check_file_path

    link = tmp_path / "gone"
    link.symlink_to(tmp_path / "missing-folder")
    with pytest.raises(OutputPathError, match=r"expected a folder at .*gone, found a link to"):
        check_file_path(link / "out.json")


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_fifo_or_a_device_is_not_replaced_by_a_file_of_results(tmp_path, kind):
    if kind == "fifo":
        target = tmp_path / "pipe"
        os.mkfifo(target)
        found = "a FIFO"
    else:
        target = Path("/dev/null")
        found = "a character device"
    with pytest.raises(OutputPathError, match=f"expected a file path, found {found}"):
        check_file_path(target)
    assert stat.S_ISFIFO(target.stat().st_mode) if kind == "fifo" else target.is_char_device()


def test_a_folder_another_process_makes_meanwhile_is_taken_as_a_folder(tmp_path, monkeypatch):
    # Two workers writing beside each other: the folder is missing when one looks, and there when
    # it looks again (another worker made it); it is a folder, not "a file".
    folder = tmp_path / "_commits"
    is_dir = Path.is_dir
    looked: list[Path] = []

    def made_meanwhile(path: Path) -> bool:
        if path == folder and not looked:
            looked.append(path)
            folder.mkdir()
            return False
        return is_dir(path)

    monkeypatch.setattr(Path, "is_dir", made_meanwhile)
    with atomic_open(folder / "episode=1.json", "w", encoding="utf-8") as handle:
        handle.write("{}")
    assert looked == [folder] and (folder / "episode=1.json").read_text() == "{}"

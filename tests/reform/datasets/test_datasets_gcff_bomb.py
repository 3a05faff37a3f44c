"""A MATLAB file that inflates beyond what a GCFF file can hold is refused before it is inflated:
its declared size at once, a lying one after counting at most the limit, never in memory."""

from __future__ import annotations

import struct
import time
import zlib
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from cli_errors import cli_peak

from reform import DataFormatError
from reform.datasets import load_gcff
from reform.datasets.gcff_mat import MAT_INFLATED_LIMIT_BYTES, check_inflated_size


def _element(mdtype: int, data: bytes) -> bytes:
    return struct.pack("<II", mdtype, len(data)) + data + b"\0" * (-len(data) % 8)


def _write_bomb(path: Path, *, zeros: int, declared: int | None = None) -> None:
    """A MATLAB 5 file with one compressed double matrix ``features`` of ``zeros`` zero bytes
    (its miMATRIX element declaring ``declared`` bytes, its true size by default), compressed a
    MiB at a time, so that the test never holds it inflated."""
    flags = _element(6, struct.pack("<II", 6, 0))  # miUINT32: mxDOUBLE_CLASS
    dims = _element(5, struct.pack("<ii", zeros // 8, 1))  # miINT32
    name = _element(1, b"features")  # miINT8
    data_tag = struct.pack("<II", 9, zeros)  # miDOUBLE
    body = len(flags) + len(dims) + len(name) + len(data_tag) + zeros
    head = struct.pack("<II", 14, body if declared is None else declared)
    # Raw deflate, a MiB of zeros compressed once and its bytes repeated (each piece ends on a
    # full flush, so each stands alone), inside a zlib header and checksum.
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    first = head + flags + dims + name + data_tag
    chunk = b"\0" * 2**20
    piece = compressor.compress(chunk) + compressor.flush(zlib.Z_FULL_FLUSH)
    whole, rest = divmod(zeros, len(chunk))
    checksum = zlib.adler32(first)
    for _ in range(whole):
        checksum = zlib.adler32(chunk, checksum)
    checksum = zlib.adler32(chunk[:rest], checksum)
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    start = compressor.compress(first) + compressor.flush(zlib.Z_FULL_FLUSH)
    end = compressor.compress(chunk[:rest]) + compressor.flush()
    compressed = b"\x78\xda" + start + piece * whole + end + struct.pack(">I", checksum)
    header = b"MATLAB 5.0 MAT-file, written by a test".ljust(116, b" ")
    header += b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    path.write_bytes(header + struct.pack("<II", 15, len(compressed)) + compressed)


def _groundtruth(folder: Path) -> None:
    cell = np.empty((1, 0), dtype=object)
    scipy.io.savemat(
        folder / "groundtruth.mat", {"GTgroups": cell, "GTtimestamp": np.zeros((1, 0))}
    )


def test_public_files_are_far_below_the_limit(shared_datasets):
    for path in sorted(shared_datasets.glob("*/**/*.mat")):
        assert 0 < check_inflated_size(path) < 100_000, path


def test_declared_bomb_refused_before_inflating(tmp_path):
    # 1 GiB of zeros in 1 MB, declaring its size: refused from its first bytes inflated.
    _write_bomb(tmp_path / "features.mat", zeros=2**30)
    _groundtruth(tmp_path)
    assert (tmp_path / "features.mat").stat().st_size < 1_100_000
    start = time.perf_counter()
    with pytest.raises(DataFormatError) as caught:
        load_gcff(tmp_path)
    assert time.perf_counter() - start < 5.0  # counted 8 bytes, not 1 GiB
    message = str(caught.value)
    assert message.startswith(f"{tmp_path / 'features.mat'}: variable 1 (at byte 128): ")
    assert "expected a MATLAB file whose variables inflate to at most" in message
    assert "found a variable declaring 1,073,741,880 bytes inflated from" in message


def test_lying_bomb_refused_at_the_limit(tmp_path):
    # It declares 200 bytes and inflates to 64 MiB: counted up to the limit, then refused.
    path = tmp_path / "features.mat"
    _write_bomb(path, zeros=64 * 2**20, declared=200)
    with pytest.raises(DataFormatError, match=r"found more than 16,777,216 bytes inflated from"):
        check_inflated_size(path, limit=16 * 2**20)
    assert check_inflated_size(path, limit=128 * 2**20) > 64 * 2**20


def test_limit_is_the_documented_one(tmp_path):
    path = tmp_path / "features.mat"
    _write_bomb(path, zeros=MAT_INFLATED_LIMIT_BYTES + 2**20, declared=200)
    with pytest.raises(DataFormatError, match="a compressed bomb"):
        check_inflated_size(path)


def test_bomb_through_the_cli_in_bounded_memory(tmp_path):
    """A real command on a 4 GiB bomb: one line, exit 2, a few hundred MB at most."""
    _write_bomb(tmp_path / "features.mat", zeros=4 * 2**30 - 2**20, declared=200)
    _groundtruth(tmp_path)
    start = time.perf_counter()
    status, err, peak = cli_peak(["data", "info", "--data", tmp_path, "--format", "gcff"])
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert "found more than" in err and "a compressed bomb" in err
    assert peak < 600 * 2**20, peak
    assert time.perf_counter() - start < 60.0


def test_the_bombs_are_real_matlab_files(tmp_path):
    # The same construction, small: scipy reads it, and the count is its size inflated.
    path = tmp_path / "features.mat"
    _write_bomb(path, zeros=3 * 2**20 + 8)
    features = scipy.io.loadmat(path)["features"]
    assert features.shape == (3 * 2**17 + 1, 1) and not features.any()
    assert check_inflated_size(path) == 8 + 56 + 3 * 2**20 + 8

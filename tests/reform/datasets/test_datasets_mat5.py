"""The MATLAB 5 reader of plain files (`reform.datasets._mat5`) answers as scipy's ``loadmat``
does, or leaves the file to it: never a different answer (issue 31: a GCFF dataset is read
without importing scipy.io)."""

from __future__ import annotations

import io
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse

from reform.datasets._isolated import IsolatedFailure, run_isolated
from reform.datasets._mat5 import read_mat5

ROOT = Path(__file__).resolve().parents[3]


def _cell(items) -> np.ndarray:
    cell = np.empty((1, len(items)), dtype=object)
    for k, item in enumerate(items):
        cell[0, k] = item
    return cell


# Shaped as a GCFF folder's files are, with the corners: an empty frame, an empty cell, a
# nested cell, integer storage.
VARIABLES = {
    "features": _cell(
        [np.array([[1, 100.0, 0, 3.1], [2, 0, 0, 0]]), np.zeros((0, 4)), np.array([[7, 1.5, 2, 0]])]
    ),
    "timestamp": np.arange(1, 4, dtype=np.float64)[None, :],
    "GTgroups": _cell(
        [_cell([np.array([[1.0, 2.0]])]), _cell([]), _cell([np.array([[1.0]]), np.array([[2.0]])])]
    ),
    "ids": np.array([[1, 2, 300]], dtype=np.int16),
    "stride": np.array([[0.7]]),
}


def _mat(variables, *, compressed: bool) -> bytes:
    buffer = io.BytesIO()
    scipy.io.savemat(buffer, variables, do_compression=compressed)
    return buffer.getvalue()


def _loadmat(path: str) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scipy.io.loadmat(path, squeeze_me=False, struct_as_record=True)


def _assert_same(mine, theirs) -> None:
    if isinstance(theirs, np.ndarray):
        assert isinstance(mine, np.ndarray)
        assert (mine.dtype.str, mine.shape) == (theirs.dtype.str, theirs.shape)
        assert mine.flags.writeable == theirs.flags.writeable
        assert mine.flags.f_contiguous == theirs.flags.f_contiguous
        if theirs.dtype == object:
            for a, b in zip(mine.ravel(order="K"), theirs.ravel(order="K"), strict=True):
                _assert_same(a, b)
        else:
            np.testing.assert_array_equal(mine, theirs)
    else:
        assert type(mine) is type(theirs)
        assert mine == theirs


def _assert_same_file(mine: dict, theirs: dict) -> None:
    assert list(mine) == list(theirs)
    for name, value in theirs.items():
        _assert_same(mine[name], value)


@pytest.mark.parametrize("compressed", [False, True], ids=["plain", "compressed"])
def test_a_gcff_shaped_file_reads_as_loadmat_reads_it(tmp_path, compressed):
    path = tmp_path / "features.mat"
    path.write_bytes(_mat(VARIABLES, compressed=compressed))
    mine = read_mat5(path.read_bytes())
    assert mine is not None
    _assert_same_file(mine, _loadmat(str(path)))


def test_every_public_gcff_file_reads_as_loadmat_reads_it(shared_datasets):
    read = 0
    for path in sorted(shared_datasets.rglob("*.mat")):
        mine = read_mat5(path.read_bytes())
        if path.name == "settings.mat":  # the original code's parameters, a struct: scipy's
            assert mine is None
            continue
        assert mine is not None, path
        _assert_same_file(mine, _loadmat(str(path)))
        read += 1
    assert read > 0


@pytest.mark.parametrize(
    "variables",
    [
        {"name": "a character array"},
        {"settings": {"stride": 0.7}},
        {"sparse": scipy.sparse.eye(3, format="csc")},
        {"complex": np.array([[1 + 2j]])},
        {"logical": np.array([[True, False]])},
        {"cells": _cell([np.array([[1.0]]), "text"])},
    ],
    ids=["char", "struct", "sparse", "complex", "logical", "cell-of-char"],
)
def test_anything_else_is_left_to_scipy(variables):
    assert read_mat5(_mat(variables, compressed=False)) is None
    assert read_mat5(_mat(variables, compressed=True)) is None


def test_a_big_endian_or_older_file_is_left_to_scipy():
    data = _mat(VARIABLES, compressed=False)
    assert read_mat5(data[:126] + b"MI" + data[128:]) is None
    assert read_mat5(b"\0\0\0\0" + data[4:]) is None  # MATLAB 4
    assert read_mat5(data[:120]) is None


def _loadmat_each(paths: list[str]) -> list[dict | str]:
    """What ``loadmat`` reads from each file, or the error it raises there."""
    answers: list[dict | str] = []
    for path in paths:
        try:
            answers.append(_loadmat(path))
        except Exception as exc:  # noqa: BLE001 - named by the test's failure
            answers.append(f"{type(exc).__name__}: {exc}")
    return answers


def _read_by_scipy(paths: list[str]) -> list[dict | str]:
    """`_loadmat_each` in one child (a damaged file can crash scipy: forking the test run once
    per file costs seconds); if the child dies, one child per file, to name the file."""
    try:
        return run_isolated(_loadmat_each, paths)
    except IsolatedFailure:
        answers: list[dict | str] = []
        for path in paths:
            try:
                answers.extend(run_isolated(_loadmat_each, [path]))
            except IsolatedFailure as exc:
                answers.append(str(exc))
        return answers


@pytest.mark.parametrize("compressed", [False, True], ids=["plain", "compressed"])
def test_a_damaged_file_is_read_as_scipy_reads_it_or_left_to_it(tmp_path, compressed):
    """Every byte after the header text changed in turn, and the file cut at every length:
    whatever the reader accepts (a changed value or padding, the variables before a cut),
    scipy reads the same way; the rest is left to scipy."""
    base = _mat(VARIABLES, compressed=compressed)
    damaged = [
        base[:position] + bytes([base[position] ^ 0x81]) + base[position + 1 :]
        for position in range(116, len(base))
    ] + [base[:size] for size in range(128, len(base))]
    accepted: dict[str, dict] = {}
    for k, data in enumerate(damaged):
        mine = read_mat5(data)
        if mine is not None:
            path = tmp_path / f"damaged-{k}.mat"
            path.write_bytes(data)
            accepted[str(path)] = mine
    assert accepted
    answers = _read_by_scipy(list(accepted))
    for (path, mine), theirs in zip(accepted.items(), answers, strict=True):
        assert not isinstance(theirs, str), f"{path}: read here, refused by scipy ({theirs})"
        _assert_same_file(mine, theirs)


def test_loading_a_gcff_dataset_imports_no_scipy(shared_datasets):
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys\n"
            "from reform.datasets import load_dataset\n"
            f"load_dataset({str(shared_datasets / 'coffeebreak')!r})\n"
            "print(sorted(m for m in ('scipy', 'scipy.io') if m in sys.modules))\n",
        ],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    assert out.stdout.splitlines()[-1] == "[]"

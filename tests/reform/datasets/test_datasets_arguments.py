"""A public loader or writer given something that is not a path (None, a number, bytes, a list,
an empty string) says so in one error naming the function and the argument, before any work."""

from __future__ import annotations

from pathlib import Path

import pytest

from reform import Dataset, Frame, load_model, save_model
from reform.datasets import (
    detect_format,
    load_babble,
    load_dante,
    load_dataset,
    load_gcff,
    load_salsa,
    read_parquet,
    registry,
    resolve,
    summarise,
    write_parquet,
)
from reform.datasets.gcff_mat import read_settings
from reform.datasets.parquet import verify_folder
from reform.persistence import model_info

DATASET = Dataset(frames=(Frame(ids=[1], position=[[0.0, 0.0]], yaw=[0.0]),), name="one")

# function name -> (call taking the bad value, the argument's name)
CALLS = {
    "load_dataset": (load_dataset, "path"),
    "detect_format": (detect_format, "path"),
    "load_dante": (load_dante, "path"),
    "load_dante groups_path": (lambda v: load_dante("x", groups_path=v), "groups_path"),
    "load_salsa": (load_salsa, "path"),
    "load_babble": (load_babble, "path"),
    "load_gcff": (load_gcff, "path"),
    "read_settings": (read_settings, "path"),
    "read_parquet": (read_parquet, "path"),
    "verify_folder": (verify_folder, "path"),
    "write_parquet": (lambda v: write_parquet(DATASET, v), "path"),
    "resolve": (resolve, "name_or_path"),
    "registry": (registry, "registry"),
    "load_model": (load_model, "path"),
    "model_info": (model_info, "path"),
}
# Arguments whose default is None.
OPTIONAL = ("load_dante groups_path", "registry")


BAD_VALUES = [
    ("None", None, TypeError, "got NoneType"),
    ("int", 3, TypeError, "got int 3"),
    ("bytes", b"/tmp", TypeError, "got bytes b'/tmp'"),
    ("list", ["a.parquet"], TypeError, r"got list \['a.parquet'\]"),
    ("empty", "", ValueError, "got an empty string"),
    ("nul", "a\0b", ValueError, r"got 'a\\x00b' \(a NUL character\)"),
]


@pytest.mark.parametrize(
    ("name", "value", "error", "found"),
    [
        pytest.param(name, value, error, found, id=f"{name}-{kind}")
        for name in CALLS
        for kind, value, error, found in BAD_VALUES
        if not (value is None and name in OPTIONAL)
    ],
)
def test_a_path_argument_that_is_no_path(name, value, error, found, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an empty string must not read the current folder
    call, argument = CALLS[name]
    function = name.split()[0]
    with pytest.raises(error, match=rf"^{function}: {argument} must be a path.*, {found}$"):
        call(value)
    assert list(Path(tmp_path).iterdir()) == []  # nothing written


def test_save_model_path_is_checked_before_anything_is_written(tmp_path):
    with pytest.raises(TypeError, match=r"^model must be a reform.Reform, got NoneType$"):
        save_model(None, tmp_path / "m.skops")


@pytest.mark.parametrize("value", [None, "data.parquet", [DATASET]], ids=["None", "str", "list"])
def test_a_dataset_argument_that_is_no_dataset(value, tmp_path):
    with pytest.raises(TypeError, match=r"^write_parquet: dataset must be a reform.Dataset or a "):
        write_parquet(value, tmp_path / "x.parquet")
    assert not (tmp_path / "x.parquet").exists()
    with pytest.raises(TypeError, match=r"^summarise: dataset must be a reform.Dataset, got "):
        summarise(value)

"""Format detection (one format per folder, else the caller names it) and DataFormatError."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

from reform import DataFormatError
from reform.datasets import detect_format, load_dataset, write_parquet


def _salsa_and_babble(salsa_dir: Path, babble_dir: Path, folder: Path) -> Path:
    """A folder holding the first lines of SALSA's files and of Babble's."""
    folder.mkdir()
    for source, name, lines in (
        (salsa_dir, "features.txt", 3),
        (salsa_dir, "group_names.txt", 3),
        (babble_dir, "Motion-capture-data.csv", 21),
    ):
        head = (source / name).read_text().splitlines()[:lines]
        (folder / name).write_text("".join(line + "\n" for line in head))
    (folder / "annotated-frames.csv").write_text("16,{[1 2 3 4 5 6 7]}\n")
    return folder


def test_a_folder_of_two_formats_is_refused(salsa_dir, babble_dir, tmp_path):
    folder = _salsa_and_babble(salsa_dir, babble_dir, tmp_path / "both")
    message = (
        r"both: expected the files of one dataset format, found salsa \(features.txt, "
        r"group_names.txt\); babble \(Motion-capture-data.csv\); name the format to read: "
        r"format='salsa' or format='babble' \(--format on the command line\)"
    )
    with pytest.raises(DataFormatError, match=message):
        detect_format(folder)
    with pytest.raises(DataFormatError, match=message):
        load_dataset(folder)
    assert load_dataset(folder, format="salsa").name == "both"  # named after its folder
    assert len(load_dataset(folder, format="babble")) == 20


def test_a_parquet_file_beside_salsa_is_ambiguous(salsa_dir, salsa_dataset, tmp_path):
    folder = tmp_path / "salsa"
    folder.mkdir()
    for name in ("features.txt", "group_names.txt"):
        (folder / name).write_bytes((salsa_dir / name).read_bytes())
    assert detect_format(folder) == "salsa"
    write_parquet(salsa_dataset, folder / "export" / "salsa.parquet")
    with pytest.raises(DataFormatError, match=r"format='salsa' or format='parquet'"):
        load_dataset(folder)
    assert load_dataset(folder, format="parquet").frames == salsa_dataset.frames


def test_data_format_error_survives_pickling():
    # Errors raised in worker processes travel back pickled.
    error = DataFormatError("a.txt", "line 1", "x", "a number", "'q'", hint="fix it")
    back = pickle.loads(pickle.dumps(error))
    assert (
        str(back) == str(error) == "a.txt: line 1: field 'x': expected a number, found 'q'; fix it"
    )
    assert (back.path, back.where, back.field, back.found) == (Path("a.txt"), "line 1", "x", "'q'")

"""A text file with a line no dataset writes (a missing newline, binary data) is refused before
the line is split: one line of error, in bounded time and memory, from a real command."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_errors import cli_peak

from reform import DataFormatError
from reform.datasets import load_babble, load_dante
from reform.datasets._validation import MAX_LINE_CHARS

PERSON = "ID_001 1.0 1.0 0.5 0.5 "


def _dante(folder: Path, features: str, groups: str = "0.2 < ID_001 >\n") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "features.txt").write_text(features)
    (folder / "group_names.txt").write_text(groups)
    return folder


def test_a_line_beyond_the_limit_is_refused_naming_it(tmp_path):
    ok_line = "0.2 " + PERSON
    folder = _dante(tmp_path / "d", ok_line + "\n" + "0.4 " + "x" * MAX_LINE_CHARS + "\n")
    with pytest.raises(DataFormatError) as caught:
        load_dante(folder)
    assert str(caught.value) == (
        f"{folder / 'features.txt'}: line 2: expected a line of at most 1,000,000 characters "
        "(a longer one is a corrupt file: a missing newline, binary data), found a longer line"
    )
    folder = _dante(tmp_path / "g", ok_line + "\n", groups="0.2 " + "< ID_001 > " * 100_000)
    with pytest.raises(DataFormatError, match=r"group_names.txt: line 1: expected a line of at"):
        load_dante(folder)


def test_babble_lines_are_bounded_too(tmp_path, babble_dir):
    head = (babble_dir / "Motion-capture-data.csv").read_text().splitlines()[0]
    (tmp_path / "Motion-capture-data.csv").write_text(head + "\n" + "1," * MAX_LINE_CHARS)
    (tmp_path / "annotated-frames.csv").write_text("1,{[1 2]}\n")
    with pytest.raises(DataFormatError, match=r"Motion-capture-data.csv: line 2: expected a line"):
        load_babble(tmp_path)


def test_a_50_mb_line_through_the_cli(tmp_path):
    """Was over a minute and 1.1 GB before its error; now refused having read 1 MB."""
    folder = _dante(tmp_path / "d", "0.2 " + PERSON * 2_200_000 + "\n")
    status, err, peak = cli_peak(["data", "info", "--data", folder])
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1 and "found a longer line" in err, err
    assert peak < 400 * 2**20, peak

"""A report's Markdown page and JSON document on disk: written whole, read back as given."""

from __future__ import annotations

import json
import math

import pytest

from sim.experiments.report_files import write_json, write_markdown


def test_markdown_is_written_as_given_into_a_new_folder(tmp_path) -> None:
    path = tmp_path / "new" / "page.md"
    text = "# Title\n\nå table | ±1 m²\n"
    assert write_markdown(path, text) == path
    assert path.read_text(encoding="utf-8") == text


@pytest.mark.parametrize("indent", [1, 2])
def test_json_reads_back_with_its_indent_and_a_final_newline(tmp_path, indent: int) -> None:
    document = {"kind": "x", "rows": [{"f1": 0.5}], "none": None}
    path = write_json(tmp_path / "doc.json", document, indent=indent)
    text = path.read_text()
    assert json.loads(text) == document
    assert text == json.dumps(document, indent=indent) + "\n"


def test_json_refuses_a_nan_and_leaves_no_file(tmp_path) -> None:
    path = tmp_path / "doc.json"
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        write_json(path, {"f1": math.nan}, indent=1)
    assert list(tmp_path.iterdir()) == []

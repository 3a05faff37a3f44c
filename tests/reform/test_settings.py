"""Detector settings files (reform.settings): written, read back as they were, and every way a
file can be wrong refused in one line naming the file, the field, what was expected and found."""

from __future__ import annotations

import json

import pytest

from reform import DetectorError, make_detector, read_settings, write_settings


def test_written_settings_read_back_as_they_were(tmp_path):
    path = write_settings(
        tmp_path / "gcff.json", "gcff", {"stride": 0.6, "mdl": 2.0}, chosen_on="a twin of salsa"
    )
    settings = read_settings(path)
    assert settings.detector == "gcff"
    assert dict(settings.options) == {"stride": 0.6, "mdl": 2.0}
    assert dict(settings.about) == {"chosen_on": "a twin of salsa"}
    detector = make_detector(settings.detector, **settings.options)
    assert (detector.stride, detector.mdl) == (0.6, 2.0)


def _file(tmp_path, document) -> str:
    path = tmp_path / "settings.json"
    path.write_text(document if isinstance(document, str) else json.dumps(document))
    return str(path)


GOOD = {
    "format": "reform-sim detector settings",
    "version": 1,
    "detector": "gcff",
    "options": {"stride": 0.6},
}


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ("{not json", "expected a JSON settings file, found text that is not JSON (Expecting"),
        ("[" * 100_000 + "]" * 100_000, "expected a JSON settings file, found JSON nested too"),
        (
            '{"version": ' + "1" * 5000 + "}",
            "expected a JSON settings file, found a number of more digits than can be read",
        ),
        ([1, 2], "expected a JSON object, found list"),
        ({**GOOD, "version": 7}, "field 'version': expected 1, found 7"),
        ({**GOOD, "format": "x"}, "field 'format': expected 'reform-sim detector settings'"),
        ({k: v for k, v in GOOD.items() if k != "options"}, "field 'options': expected it"),
        ({**GOOD, "detector": "oracle"}, "field 'detector': unknown detector 'oracle'"),
        (
            {**GOOD, "options": {"stride": 99}},
            "field 'options.stride': detector 'gcff': option "
            "stride expects a float in m from 0.01 to 10, got a int (99)",
        ),
        ({**GOOD, "options": {"size": 3}}, "field 'options.size': detector 'gcff' has no option"),
        (
            {**GOOD, "options": {"stride": None}},
            "field 'options.stride': detector 'gcff': option stride expects a float in m from "
            "0.01 to 10, got null",
        ),
    ],
    ids=[
        "not-json",
        "nested-too-deep",  # was a RecursionError traceback
        "number-of-5000-digits",  # was a message naming no file
        "not-object",
        "version",
        "format",
        "no-options",
        "detector",
        "range",
        "unknown",
        "null",  # was refused by the detector at its first frame, naming no file
    ],
)
def test_a_bad_settings_file_is_one_line(tmp_path, document, message):
    path = _file(tmp_path, document)
    with pytest.raises(DetectorError) as caught:
        read_settings(path)
    text = str(caught.value)
    assert text.startswith(f"{path}: ") and message in text
    assert "\n" not in text


def test_writing_checks_the_values_against_the_catalogue(tmp_path):
    with pytest.raises(DetectorError, match="option stride expects a float in m"):
        write_settings(tmp_path / "x.json", "gcff", {"stride": -1.0})
    assert not (tmp_path / "x.json").exists()

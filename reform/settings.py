"""Detector settings files: a catalogued detector's name and the values of its options, as JSON.

What a settings search writes (``reform-sim tune``, a grid search on training frames) and what
``detect``, ``evaluate`` and ``benchmark`` take as they are (``--settings FILE.json``)::

    {
      "format": "reform-sim detector settings",
      "version": 1,
      "detector": "gcff",
      "options": {"stride": 0.6, "mdl": 2.0},
      "chosen_on": "twin of salsa (generated, no labels of salsa read)"
    }

``options`` are checked against the catalogue's declaration of the detector
(`reform.detectors.Option`: type and range) when the file is read; any other key is provenance,
kept as it is. Pure Python: reading a settings file imports no numerical library.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from reform.detectors import DetectorError, detector_info
from reform.json_values import JsonError, parse_json

__all__ = ["SETTINGS_FORMAT", "SETTINGS_VERSION", "Settings", "read_settings", "write_settings"]

SETTINGS_FORMAT = "reform-sim detector settings"
SETTINGS_VERSION = 1
_REQUIRED = ("format", "version", "detector", "options")


@dataclass(frozen=True)
class Settings:
    """A detector and its options, read from a settings file.

    Attributes:
        detector: the catalogue's name.
        options: option name -> value, each checked against the catalogue.
        about: the file's other keys (provenance: what chose the values, on which data).
    """

    detector: str
    options: Mapping[str, Any]
    about: Mapping[str, Any] = field(default_factory=dict)


def _refuse(path: Path, what: str) -> DetectorError:
    return DetectorError(f"{path}: {what}")


def read_settings(path: str | os.PathLike[str]) -> Settings:
    """The settings file at ``path``, checked against the catalogue.

    Raises:
        DetectorError: one line naming the file, the field, what was expected and what was
            found: not JSON, another format or version, an unknown detector or option, a value
            of the wrong type or out of its range.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise _refuse(path, f"cannot read the settings file ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise _refuse(
            path, "expected a JSON settings file, found bytes that are not UTF-8"
        ) from None
    try:
        document = parse_json(text)
    except JsonError as exc:
        raise _refuse(path, f"expected a JSON settings file, found {exc}") from None
    if not isinstance(document, dict):
        raise _refuse(path, f"expected a JSON object, found {type(document).__name__}")
    missing = [key for key in _REQUIRED if key not in document]
    if missing:
        raise _refuse(path, f"field {missing[0]!r}: expected it, found no such field")
    if document["format"] != SETTINGS_FORMAT:
        raise _refuse(
            path, f"field 'format': expected {SETTINGS_FORMAT!r}, found {document['format']!r}"
        )
    if document["version"] != SETTINGS_VERSION:
        raise _refuse(
            path, f"field 'version': expected {SETTINGS_VERSION}, found {document['version']!r}"
        )
    name = document["detector"]
    if not isinstance(name, str) or ":" in name:
        raise _refuse(path, f"field 'detector': expected a catalogued detector, found {name!r}")
    try:
        info = detector_info(name)
    except DetectorError as exc:
        raise _refuse(path, f"field 'detector': {exc}") from None
    options = document["options"]
    if not isinstance(options, dict):
        raise _refuse(path, f"field 'options': expected an object, found {options!r}")
    checked = {}
    for key, value in options.items():
        try:
            option = info.option(key)
            if value is None:  # a settings file states values: null would reach the factory
                raise DetectorError(
                    f"detector {name!r}: option {key} expects {option.expects()}, got null"
                )
            checked[key] = option.check(name, value)
        except DetectorError as exc:
            raise _refuse(path, f"field 'options.{key}': {exc}") from None
    about = {k: v for k, v in document.items() if k not in _REQUIRED}
    return Settings(detector=name, options=checked, about=about)


def write_settings(
    path: str | os.PathLike[str], detector: str, options: Mapping[str, Any], **about: Any
) -> Path:
    """Writes a settings file (atomically) that :func:`read_settings` reads back as it was.

    Args:
        path: the file to write (``.json``).
        detector: the catalogue's name.
        options: the option values, checked against the catalogue now.
        **about: provenance kept beside them (JSON values): what chose them, on which data.

    Returns:
        The path written.

    Raises:
        DetectorError: an unknown detector or option, a value out of its range.
    """
    from reform.atomic import atomic_open

    info = detector_info(detector)
    checked = {key: info.option(key).check(detector, value) for key, value in options.items()}
    clash = sorted(set(about) & set(_REQUIRED))
    if clash:
        raise ValueError(f"about may not hold {clash}: they are the file's own fields")
    document = {
        "format": SETTINGS_FORMAT,
        "version": SETTINGS_VERSION,
        "detector": detector,
        "options": {
            k: os.fspath(v) if isinstance(v, os.PathLike) else v for k, v in checked.items()
        },
        **about,
    }
    with atomic_open(path, "w", encoding="utf-8") as handle:
        handle.write(json.dumps(document, indent=2, sort_keys=False) + "\n")
    return Path(path)

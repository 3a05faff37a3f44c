"""A venue twin, frozen: the scenario and its options, the annotation model, and what fixed them.

``twin.json`` holds one `Twin`: every value the fit chose (scenario options, annotation settings,
rate, episodes), and beside each the statistic that fixed it with the real recording's figure
and the twin's. `read_twin` refuses a file edited into nonsense (an unknown field, a value out of
its range, an unknown version) in one line naming the file, the field, what was expected and
what was found, before any work starts.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

from reform.annotation import AnnotationModel
from reform.atomic import atomic_open
from reform.json_values import JsonError, parse_json

__all__ = [
    "MODES",
    "TWIN_FORMAT",
    "TWIN_VERSION",
    "Fitted",
    "Twin",
    "TwinFormatError",
    "read_twin",
    "twin_from_json",
    "write_twin",
]

TWIN_FORMAT = "reform-sim venue twin"
TWIN_VERSION = 1
MODES = ("label-free", "labels")  # label-free: frames only; labels: --use-labels
MAX_RATE_HZ = 100.0  # frames per second a twin may be generated at
MAX_EPISODES = 1000
MAX_SEED = 2**63 - 1


class TwinFormatError(ValueError):
    """A twin file that cannot be used: one line naming the file, field, expected, found."""


@dataclass(frozen=True)
class Fitted:
    """One fitted value and the statistic that fixed it.

    Attributes:
        name: what was fitted (``options.people``, ``annotation.scale``, ``rate_hz``, ...).
        value: the value chosen.
        statistic: the statistic matched, in words.
        real: the statistic on the real recording (None where it is not measured).
        twin: the statistic on the twin's own frames.
    """

    name: str
    value: Any
    statistic: str
    real: Any
    twin: Any

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "value": self.value,
            "statistic": self.statistic,
            "real": self.real,
            "twin": self.twin,
        }


@dataclass(frozen=True)
class Twin:
    """A venue twin.

    Attributes:
        name: the recording it was fitted to (the dataset's name).
        mode: ``"label-free"`` (frames only) or ``"labels"`` (group structure fitted too).
        scenario: registered scenario name.
        options: every option of the scenario (checked by `scenarios.registry.check_options`).
        annotation: how the twin's frames are recorded (`reform.annotation.AnnotationModel`).
        rate_hz: frames per second generated.
        episodes: episodes generated.
        seed: master seed of the generated data.
        fitted: each fitted value with its statistic, real and twin.
        statistics: the label-free statistics, ``{"real": {...}, "twin": {...}}``.
    """

    name: str
    mode: str
    scenario: str
    options: Mapping[str, Any]
    annotation: AnnotationModel
    rate_hz: float
    episodes: int
    seed: int = 0
    fitted: tuple[Fitted, ...] = ()
    statistics: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "options", MappingProxyType(dict(self.options)))
        object.__setattr__(self, "statistics", MappingProxyType(dict(self.statistics)))

    def to_json(self) -> dict[str, Any]:
        annotation = {f.name: getattr(self.annotation, f.name) for f in fields(AnnotationModel)}
        return {
            "format": TWIN_FORMAT,
            "version": TWIN_VERSION,
            "name": self.name,
            "mode": self.mode,
            "scenario": self.scenario,
            "options": dict(self.options),
            "annotation": annotation,
            "rate_hz": self.rate_hz,
            "episodes": self.episodes,
            "seed": self.seed,
            "fitted": [f.to_json() for f in self.fitted],
            "statistics": {k: dict(v) for k, v in self.statistics.items()},
        }


def write_twin(twin: Twin, path: str | os.PathLike[str]) -> Path:
    """Writes ``twin`` as JSON (atomically: whole or absent); the same twin, the same bytes."""
    path = Path(path)
    text = json.dumps(twin.to_json(), indent=2, sort_keys=False, allow_nan=False) + "\n"
    with atomic_open(path, "w", encoding="utf-8") as handle:
        handle.write(text)
    return path


def read_twin(path: str | os.PathLike[str]) -> Twin:
    """The twin in ``path``, checked field by field.

    Raises:
        TwinFormatError: a missing or unreadable file, not JSON, an unknown version or field, a
            field given twice or left out (a twin lists every value it was fitted with; only
            an annotation scale of 1 is left out), a value out of its range, options that do
            not go together (`scenarios.registry.check_together`): one line naming the file,
            the field, expected and found.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TwinFormatError(
            f"{path}: no such twin file (make one with `reform-sim twin --data DATASET`)"
        ) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TwinFormatError(f"{path}: cannot read the twin file: {exc}") from None
    try:
        data = parse_json(text, object_pairs_hook=_once_each)
    except JsonError as exc:
        raise TwinFormatError(f"{path}: expected a twin file (JSON), found {exc}") from None
    except _Repeated as exc:
        raise _fail(str(path), str(exc), "the field once", "it twice") from None
    return twin_from_json(data, where=str(path))


class _Repeated(ValueError):
    """A JSON object with a field given twice (its name)."""


def _once_each(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object's fields, each given once (JSON would keep the last of two silently)."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _Repeated(key)
        out[key] = value
    return out


_TOP = (
    "format",
    "version",
    "name",
    "mode",
    "scenario",
    "options",
    "annotation",
    "rate_hz",
    "episodes",
    "seed",
    "fitted",
    "statistics",
)


_OMITTED_AT_DEFAULT = ("scale",)  # annotation settings written only when not at their default
# (`reform.annotation.AnnotationModel.to_json`)


def _fail(where: str, name: str, expected: str, found: Any) -> TwinFormatError:
    return TwinFormatError(f"{where}: field {name}: expected {expected}, found {found!r}")


def _number(where: str, name: str, value: Any, low: float, high: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _fail(where, name, f"a number in ({low:g}, {high:g}]", value)
    if not low < value <= high:
        raise _fail(where, name, f"a number in ({low:g}, {high:g}]", value)
    return float(value)


def _integer(where: str, name: str, value: Any, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise _fail(where, name, f"a whole number from {low} to {high}", value)
    return value


def twin_from_json(data: Any, *, where: str = "twin") -> Twin:
    """A `Twin` from the JSON value ``data`` (as `read_twin` checks it)."""
    import scenarios

    if not isinstance(data, dict):
        raise _fail(where, "(top level)", "a JSON object", type(data).__name__)
    unknown = [k for k in data if k not in _TOP]
    if unknown:
        raise _fail(where, unknown[0], f"one of the fields {list(_TOP)}", unknown[0])
    missing = [k for k in _TOP if k not in data]
    if missing:
        raise _fail(where, missing[0], "the field to be present", "nothing")
    if data["format"] != TWIN_FORMAT:
        raise _fail(where, "format", repr(TWIN_FORMAT), data["format"])
    if type(data["version"]) is not int or data["version"] != TWIN_VERSION:  # not true, 1.0
        raise _fail(where, "version", f"{TWIN_VERSION} (the version this reform-sim reads)",
                    data["version"])  # fmt: skip
    for name in ("name", "scenario"):
        if not isinstance(data[name], str) or not data[name]:
            raise _fail(where, name, "a non-empty string", data[name])
    if data["mode"] not in MODES:
        raise _fail(where, "mode", f"one of {list(MODES)}", data["mode"])
    if data["scenario"] not in scenarios.names():
        raise _fail(where, "scenario", f"a registered scenario {list(scenarios.names())}",
                    data["scenario"])  # fmt: skip
    options = data["options"]
    if not isinstance(options, dict):
        raise _fail(where, "options", "an object of scenario options", options)
    try:
        checked = scenarios.registry.check_options(data["scenario"], options)
    except ValueError as exc:
        raise TwinFormatError(f"{where}: field options: {exc}") from None
    absent = [name for name in checked if name not in options]
    if absent:  # a twin lists every option it was fitted with: none is left to a default
        raise _fail(
            where, f"options.{absent[0]}", f"a value (every option of {data['scenario']})",
            "nothing",
        )  # fmt: skip
    annotation = data["annotation"]
    if not isinstance(annotation, dict):
        raise _fail(where, "annotation", "an object of annotation settings", annotation)
    known = [f.name for f in fields(AnnotationModel)]
    extra = [k for k in annotation if k not in known]
    if extra:
        raise _fail(where, f"annotation.{extra[0]}", f"one of {known}", extra[0])
    absent = [k for k in known if k not in annotation and k not in _OMITTED_AT_DEFAULT]
    if absent:
        raise _fail(where, f"annotation.{absent[0]}", "a value (every setting but scale)",
                    "nothing")  # fmt: skip
    try:
        model = AnnotationModel(**annotation)
    except (TypeError, ValueError) as exc:
        raise TwinFormatError(f"{where}: field annotation: {exc}") from None
    rate = _number(where, "rate_hz", data["rate_hz"], 0.0, MAX_RATE_HZ)
    from sim.world import steps_per_frame, whole_step_rates

    try:  # generated frames fall on the world's control steps only
        steps_per_frame(rate)
    except ValueError:
        raise _fail(where, "rate_hz", whole_step_rates(), data["rate_hz"]) from None
    length = checked.get("duration")  # seconds of each episode, as generate reads them
    if isinstance(length, (int, float)):
        if length * rate < 1.0 - 1e-9:
            raise _fail(
                where,
                "rate_hz",
                f"a rate at which an episode of options.duration {length:g} s holds a frame "
                f"(at least {1.0 / length:g} Hz)",
                data["rate_hz"],
            )
        if model.min_group_seconds >= length:
            raise _fail(
                where,
                "annotation.min_group_seconds",
                f"less than an episode (options.duration {length:g} s)",
                annotation["min_group_seconds"],
            )
    episodes = _integer(where, "episodes", data["episodes"], 1, MAX_EPISODES)
    seed = _integer(where, "seed", data["seed"], 0, MAX_SEED)
    try:  # options each in range may not go together (a party too large for its room)
        scenarios.registry.check_together(data["scenario"], checked)
    except ValueError as exc:
        raise TwinFormatError(f"{where}: field options: {exc}") from None
    fitted = data["fitted"]
    if not isinstance(fitted, list):
        raise _fail(where, "fitted", "a list of fitted values", fitted)
    records = []
    keys = ("name", "value", "statistic", "real", "twin")
    for k, item in enumerate(fitted):
        if not isinstance(item, dict) or sorted(item) != sorted(keys):
            raise _fail(where, f"fitted[{k}]", f"an object with the fields {list(keys)}", item)
        records.append(Fitted(**item))
    statistics = data["statistics"]
    if not isinstance(statistics, dict) or any(
        not isinstance(v, dict) for v in statistics.values()
    ):
        raise _fail(where, "statistics", "an object of statistics objects", statistics)
    return Twin(
        name=data["name"],
        mode=data["mode"],
        scenario=data["scenario"],
        options=checked,
        annotation=model,
        rate_hz=rate,
        episodes=episodes,
        seed=seed,
        fitted=tuple(records),
        statistics=statistics,
    )

"""Numbers as JSON can hold them: the results' ``to_json`` methods write floats through here."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

__all__ = ["json_float", "json_record", "json_value"]


def json_float(value: float | None) -> float | None:
    """``value`` as JSON can hold it: a float, or None (null) for None, NaN or an infinity."""
    return None if value is None or not math.isfinite(value) else float(value)


def json_value(value: Any) -> Any:
    """One field of a result as JSON holds it: a record by its own ``to_json()``, a float
    through `json_float`, a tuple as a list and a mapping as a dict of such values; anything
    else as it is."""
    if hasattr(value, "to_json"):
        return value.to_json()
    if isinstance(value, float):
        return json_float(value)
    if isinstance(value, tuple):
        return [json_value(v) for v in value]
    if isinstance(value, Mapping):
        return {k: json_value(v) for k, v in value.items()}
    return value


def json_record(record: Any, names: Mapping[str, str] | None = None, /, **values: Any) -> dict:
    """A frozen dataclass of results as a JSON object: its fields in the order declared, each
    under its name (or the key ``names`` gives it) as `json_value` writes it, or as ``values``
    gives it for the fields that need more (a mapping of records, a count of a tuple)."""
    fields = [f.name for f in dataclasses.fields(record)]
    unknown = sorted(set(values).union(names or {}).difference(fields))
    if unknown:
        raise TypeError(f"{type(record).__name__} has no field {', '.join(unknown)}")
    keys = names or {}
    return {
        keys.get(name, name): values[name] if name in values else json_value(getattr(record, name))
        for name in fields
    }

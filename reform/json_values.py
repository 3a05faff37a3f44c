"""Numbers as JSON can hold them: the results' ``to_json`` methods write floats through here;
and JSON read from a file (`parse_json`), whatever it holds, as a value or one `JsonError`."""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from typing import Any

__all__ = ["JsonError", "json_float", "json_record", "json_value", "parse_json"]


class JsonError(ValueError):
    """Text that is not JSON that can be read; ``str`` says what was found instead (``text
    that is not JSON (Expecting value at line 1, column 1)``, ``JSON nested too deep to
    read``), for a caller's message naming its file."""


def parse_json(text: str | bytes, **options: Any) -> Any:
    """``json.loads(text, **options)`` (bytes read as UTF-8), or one `JsonError` for every way a
    file's text can fail to be read: not JSON, bytes that are not UTF-8, arrays and objects
    nested deeper than Python's recursion allows, a number of more digits than Python reads
    (4,300). What an ``options`` hook raises passes through as it is."""
    try:
        if isinstance(text, bytes):  # UTF-8, as every JSON file here is written
            text = text.decode("utf-8")
        return json.loads(text, **options)
    except json.JSONDecodeError as exc:
        raise JsonError(
            f"text that is not JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})"
        ) from None
    except UnicodeDecodeError:
        raise JsonError("bytes that are not UTF-8 text") from None
    except RecursionError:
        raise JsonError("JSON nested too deep to read") from None
    except ValueError as exc:
        if type(exc) is not ValueError:  # a hook's own error
            raise
        if "integer string conversion" in str(exc):
            raise JsonError("a number of more digits than can be read (4,300)") from None
        raise JsonError(f"JSON that cannot be read ({exc})") from None


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

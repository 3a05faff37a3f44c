"""Numbers as JSON can hold them: the results' ``to_json`` methods write floats through here."""

from __future__ import annotations

import math

__all__ = ["json_float"]


def json_float(value: float | None) -> float | None:
    """``value`` as JSON can hold it: a float, or None (null) for None, NaN or an infinity."""
    return None if value is None or not math.isfinite(value) else float(value)

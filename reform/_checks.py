"""Argument checks shared by the models of annotation and tracking errors."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = ["check_levels", "non_negative"]


def non_negative(label: str, value: Any, *, high: float | None = None) -> float:
    """``value`` as a float, checked to be a finite number >= 0 (and <= ``high`` when given).

    Args:
        label: what the value is, as messages name it (``"TrackerNoise.dropout"``).
        value: an int or float (numpy's too); a bool is not a number here.
        high: the largest value allowed, or None for no bound above.

    Raises:
        ValueError: ``"<label> must be a number, got 'a'"``, ``"<label> must be a finite number
            >= 0, got inf"`` or ``"<label> must be in [0, 1], got 1.5"``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{label} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value) or value < 0.0 or (high is not None and value > high):
        bound = f"in [0, {high:g}]" if high is not None else "a finite number >= 0"
        raise ValueError(f"{label} must be {bound}, got {value!r}")
    return value


def check_levels(
    record: Any, prefix: str, levels: Iterable[str], *, probabilities: Iterable[str] = ()
) -> None:
    """Checks fields of the frozen dataclass ``record``, each replaced by its float.

    Args:
        record: the dataclass instance (in its ``__post_init__``).
        prefix: what messages put before a field's name (``"TrackerNoise."``).
        levels: fields that must be finite numbers >= 0 (noise levels), checked first.
        probabilities: fields that must be in [0, 1], checked next.

    Raises:
        ValueError: as :func:`non_negative`, for the first field outside its range.
    """
    for names, high in ((levels, None), (probabilities, 1.0)):
        for name in names:
            value = non_negative(f"{prefix}{name}", getattr(record, name), high=high)
            object.__setattr__(record, name, value)

"""Checks of the field detectors' parameters (proximity, dominant sets, GTCG, Hough voting).

Each detector checks its parameters when it predicts, as a scikit-learn estimator does, and a
bad value is one ``ValueError`` line naming the parameter, what is accepted and what came. The
catalogue (`reform.catalogue`) declares the same ranges for the command line.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from reform.frame import Frame

__all__ = ["check_choice", "check_number", "orientation_of"]

ORIENTATIONS = ("body", "head")


def check_number(
    name: str, value: Any, *, low: float, high: float, integer: bool = False, open_low: bool = False
) -> float:
    """``value`` as a float (an int with ``integer``) inside ``[low, high]`` (``(low, high]``
    with ``open_low``); else ValueError naming ``name``, the range and the value."""
    kind = "an integer" if integer else "a number"
    bracket = "(" if open_low else "["
    expected = f"{kind} in {bracket}{low:g}, {high:g}]"
    ok = not isinstance(value, (bool, np.bool_)) and isinstance(
        value, (int, float, np.integer, np.floating)
    )
    if ok:
        number = float(value)
        ok = bool(np.isfinite(number)) and (number > low if open_low else number >= low)
        ok = ok and number <= high and (not integer or number == int(number))
    if not ok:
        raise ValueError(f"{name} must be {expected}, got {value!r}")
    return int(value) if integer else float(value)


def check_choice(name: str, value: Any, choices: Sequence[str]) -> str:
    """``value`` when it is one of ``choices``; else ValueError listing them."""
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(choices)}, got {value!r}")
    return value


def orientation_of(frame: Frame, orientation: str) -> np.ndarray:
    """(n,) yaws (radians) a detector reads: body yaws, or head yaws where the head was seen and
    body yaws where it was not (NaN); as `reform.Gcff` reads them.

    Raises:
        ValueError: ``orientation="head"`` on a frame without head yaws, naming the frame.
    """
    if orientation == "body":
        return frame.yaw
    if frame.head_yaw is None:
        where = f" of {frame.sequence!r}" if frame.sequence else ""
        raise ValueError(
            f"orientation='head' needs head yaws, but the frame at time {frame.time:g} s{where} "
            "has none"
        )
    return np.where(np.isfinite(frame.head_yaw), frame.head_yaw, frame.yaw)

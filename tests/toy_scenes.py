"""Small synthetic scenes for the tests: circles of people facing their centre, and loners.

The detector checks' scenes (`reform.detector_checks.circle_frame`), named ``toy`` here. Not a
simulator (see ``sim/`` and ``scenarios/``): just enough structure for a classifier to learn from
in a fraction of a second.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from reform import Frame
from reform.detector_checks import GROUP_RADIUS_M, circle_frame

__all__ = ["GROUP_RADIUS_M", "line_frame", "toy_frame", "toy_frames"]


def toy_frame(rng: np.random.Generator, *, sequence: str = "toy", **kwargs: Any) -> Frame:
    """A frame with one circular F-formation per entry of ``sizes`` and ``loners`` singletons."""
    return circle_frame(rng, sequence=sequence, **kwargs)


def toy_frames(seed: int, count: int, **kwargs: Any) -> list[Frame]:
    """``count`` toy frames from one seed, times 0, 1, 2, ... seconds."""
    rng = np.random.default_rng(seed)
    return [toy_frame(rng, time=float(t), **kwargs) for t in range(count)]


def line_frame(ids, groups, *, time: float = 0.0, sequence: str = "s") -> Frame:
    """A frame with people on a line, 1 m apart; for tests where only ids and groups matter."""
    ids = list(ids)
    n = len(ids)
    return Frame(
        ids=ids,
        position=np.c_[np.arange(n, dtype=float), np.zeros(n)],
        yaw=np.zeros(n),
        groups=groups,
        time=time,
        sequence=sequence,
    )

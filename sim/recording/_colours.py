"""Colours shared by the recording's entity trees (sRGB, 0-255, RGBA)."""

from __future__ import annotations

import numpy as np

# Tableau 10 then its light variants: distinct group colours that read on a dark background.
GROUP_PALETTE = np.array(
    [
        (78, 121, 167),
        (242, 142, 43),
        (225, 87, 89),
        (118, 183, 178),
        (89, 161, 79),
        (237, 201, 72),
        (176, 122, 161),
        (255, 157, 167),
        (156, 117, 95),
        (186, 176, 172),
        (160, 203, 232),
        (255, 190, 125),
        (140, 209, 125),
        (182, 153, 45),
        (134, 188, 182),
        (241, 206, 99),
        (212, 166, 200),
        (250, 191, 210),
        (215, 181, 166),
        (121, 112, 110),
    ],
    dtype=np.uint8,
)

SINGLETON = (110, 110, 110, 255)  # people in no F-formation
HUMAN = (214, 200, 178, 255)
ROBOT = (70, 150, 230, 255)
OBSERVED = (250, 250, 250, 255)
BODY_FACING = (240, 140, 40, 255)
HEAD_FACING = (90, 190, 250, 255)
TRAIL = (200, 200, 200, 160)
FIELD_OF_VIEW = (70, 150, 230, 255)
MISSED = (230, 40, 40, 255)
SPURIOUS = (230, 40, 230, 255)
EXTRA_MEMBER = (255, 150, 0, 255)
MISSING_MEMBER = (230, 40, 40, 255)
FLOOR = (60, 60, 66, 255)
WALL = (150, 150, 160, 255)

# One colour per detector in the plots, in the order the detectors are given; truth is white.
TRUTH_SERIES = (235, 235, 235, 255)
SERIES_PALETTE = GROUP_PALETTE[[1, 0, 4, 2, 6, 3, 5, 8]]

APART = (80, 120, 200, 255)  # pair label 0
TOGETHER = (240, 140, 40, 255)  # pair label 1


def group_colour(track: int) -> tuple[int, int, int, int]:
    """Colour of group track ``track`` (1, 2, ...); 0 is the singleton grey."""
    if track <= 0:
        return SINGLETON
    r, g, b = GROUP_PALETTE[(track - 1) % len(GROUP_PALETTE)]
    return (int(r), int(g), int(b), 255)


def series_colour(index: int) -> tuple[int, int, int, int]:
    """Colour of the ``index``-th detector's plot lines."""
    r, g, b = SERIES_PALETTE[index % len(SERIES_PALETTE)]
    return (int(r), int(g), int(b), 255)

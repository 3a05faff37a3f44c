"""Colours shared by the recording's entity trees, the figures and the environments' frames
(sRGB, 0-255, RGBA).

Groups are coloured by track: the ground truth's F-formations take tracks 1, 2, ...; a
detected F-formation matched to a true one (`reform.match_groups`: the one-to-one assignment
of largest summed Jaccard index) takes that group's track, so a matched group wears one colour
in the truth and in every detector; an unmatched one takes a track of its own (`match_tracks`).
"""

from __future__ import annotations

import colorsys
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from reform.matching import match_groups

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


_GOLDEN_TURN = 0.618033988749895  # of a full hue circle: successive hues stay far apart


def group_colour(track: int) -> tuple[int, int, int, int]:
    """Colour of group track ``track`` (1, 2, ...); 0 is the singleton grey.

    The first tracks take the palette's colours; later ones take hues a golden turn apart
    (saturated, mid-light), so no two tracks of a run share a colour.
    """
    if track <= 0:
        return SINGLETON
    if track <= len(GROUP_PALETTE):
        r, g, b = GROUP_PALETTE[track - 1]
        return (int(r), int(g), int(b), 255)
    hue = ((track - len(GROUP_PALETTE)) * _GOLDEN_TURN) % 1.0
    value = 0.95 if track % 2 else 0.75
    r, g, b = (round(255 * c) for c in colorsys.hsv_to_rgb(hue, 0.65, value))
    return (r, g, b, 255)


def fformations(partition: Iterable[Iterable[int]]) -> list[tuple[int, ...]]:
    """The F-formations of a partition (its groups of two or more), as tuples of ids."""
    groups = (tuple(int(m) for m in group) for group in partition)
    return [group for group in groups if len(group) >= 2]


def match_tracks(
    truth: Iterable[Iterable[int]] | None,
    detections: Mapping[str, Iterable[Iterable[int]]],
) -> tuple[list[int], dict[str, list[int]]]:
    """Tracks (colour classes) of the F-formations of one frame's truth and detections.

    Args:
        truth: the true partition (or its F-formations); None when unknown.
        detections: detector name -> its partition of the frame.

    Returns:
        The truth's tracks (1, 2, ... in order of its F-formations) and, per detector, the
        track of each of its F-formations in order: the matched true group's track, or a
        track no true group has; a detected group with the same members as an unmatched group
        of an earlier detector shares its track.
    """
    true_groups = fformations(truth or ())
    true_tracks = list(range(1, len(true_groups) + 1))
    next_track = len(true_groups) + 1
    extra: dict[frozenset[int], int] = {}
    out: dict[str, list[int]] = {}
    for name, partition in detections.items():
        groups = fformations(partition)
        tracks = []
        for group, match in zip(groups, match_groups(true_groups, groups), strict=True):
            if match is not None:
                tracks.append(true_tracks[match])
                continue
            key = frozenset(group)
            if key not in extra:
                extra[key] = next_track
                next_track += 1
            tracks.append(extra[key])
        out[name] = tracks
    return true_tracks, out


def colour_of_groups(
    groups: Sequence[Sequence[int]], tracks: Sequence[int]
) -> dict[int, tuple[int, int, int, int]]:
    """Person id -> the colour of their F-formation's track."""
    return {
        int(m): group_colour(track)
        for group, track in zip(groups, tracks, strict=True)
        for m in group
    }


def series_colour(index: int) -> tuple[int, int, int, int]:
    """Colour of the ``index``-th detector's plot lines."""
    r, g, b = SERIES_PALETTE[index % len(SERIES_PALETTE)]
    return (int(r), int(g), int(b), 255)

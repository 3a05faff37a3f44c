"""The groups an environment draws over its scene: rings on the floor, one colour per group.

`group_rings` turns the ground truth's F-formations and the robot's last detection into rings
around each group: the truth's wide and thick, the detection's inside them and thinner, in
the colours of `sim.recording` (a detected group matched to a true one wears its colour,
`sim.recording.match_tracks`). `draw_rings` paints them onto a rendered frame by projecting
them through the MuJoCo camera the frame was rendered with; the human render mode logs the
same rings to Rerun.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sim.recording import fformations, group_colour, match_tracks

__all__ = ["GroupRing", "draw_rings", "group_rings", "project", "ring_points"]

TRUTH_MARGIN_M = 0.35  # metres: a true group's ring runs this far outside its members' circle
DETECTED_MARGIN_M = 0.2  # metres: a detected group's ring, inside the truth's
TRUTH_WIDTH_PX = 3  # pixels: half-thickness of a true group's ring
DETECTED_WIDTH_PX = 2  # pixels: half-thickness of a detected group's ring
RING_Z_M = 0.02  # metres above the floor
RING_POINTS = 96  # points around a ring


@dataclass(frozen=True)
class GroupRing:
    """One group's ring on the floor.

    Attributes:
        source: ``"truth"`` or the detector's name.
        members: the group's person ids.
        centre: (2,) metres, the mean of the members' positions.
        radius: metres: the members' mean distance from the centre plus the source's margin.
        colour: sRGB 0-255 RGBA, the group's track colour.
        width_px: half-thickness when drawn onto a frame, pixels.
    """

    source: str
    members: tuple[int, ...]
    centre: np.ndarray
    radius: float
    colour: tuple[int, int, int, int]
    width_px: int


def group_rings(
    ids: Sequence[int],
    position: np.ndarray,
    truth: Iterable[Iterable[int]] | None,
    detections: Mapping[str, Iterable[Iterable[int]]],
) -> list[GroupRing]:
    """Rings of the true F-formations and of each detector's, coloured by matched track.

    Args:
        ids: (n,) person ids of the rows of ``position``.
        position: (n, 2) metres, everyone's true position now.
        truth: the true groups now (None: unknown).
        detections: detector name -> its last partition.

    Returns:
        The truth's rings, then each detector's, in partition order; members not in ``ids``
        are left out (a group with fewer than two left is not drawn).
    """
    row = {int(i): k for k, i in enumerate(ids)}
    true_groups = fformations(truth or ())
    true_tracks, tracks = match_tracks(true_groups, detections)
    sources = [("truth", true_groups, true_tracks, TRUTH_MARGIN_M, TRUTH_WIDTH_PX)]
    for name, partition in detections.items():
        sources.append(
            (name, fformations(partition), tracks[name], DETECTED_MARGIN_M, DETECTED_WIDTH_PX)
        )
    out = []
    for source, groups, group_tracks, margin, width in sources:
        for group, track in zip(groups, group_tracks, strict=True):
            rows = [row[m] for m in group if m in row]
            if len(rows) < 2:
                continue
            where = position[rows]
            centre = where.mean(axis=0)
            spread = float(np.mean(np.hypot(*(where - centre).T)))
            out.append(
                GroupRing(
                    source=source,
                    members=tuple(group),
                    centre=centre,
                    radius=spread + margin,
                    colour=group_colour(track),
                    width_px=width,
                )
            )
    return out


def ring_points(ring: GroupRing, *, z: float = RING_Z_M, n: int = RING_POINTS) -> np.ndarray:
    """(n + 1, 3) metres: the ring as a closed polyline on the floor at height ``z``."""
    angle = np.linspace(0.0, 2.0 * math.pi, n + 1)
    out = np.empty((n + 1, 3))
    out[:, 0] = ring.centre[0] + ring.radius * np.cos(angle)
    out[:, 1] = ring.centre[1] + ring.radius * np.sin(angle)
    out[:, 2] = z
    return out


def project(points: np.ndarray, cameras: Sequence[object], width: int, height: int) -> np.ndarray:
    """(n, 2) pixel coordinates (column, row; NaN behind the camera) of world points (n, 3).

    Args:
        points: (n, 3) metres.
        cameras: the scene's OpenGL cameras (``mujoco.MjvScene.camera``, the two eyes): a mono
            frame is seen from their mean.
        width, height: the frame's size, pixels.
    """
    pos = np.mean([np.asarray(c.pos, dtype=np.float64) for c in cameras], axis=0)
    forward = np.asarray(cameras[0].forward, dtype=np.float64)
    up = np.asarray(cameras[0].up, dtype=np.float64)
    right = np.cross(forward, up)
    camera = cameras[0]
    near = float(camera.frustum_near)
    bottom, top = float(camera.frustum_bottom), float(camera.frustum_top)
    half_h = 0.5 * (top - bottom)
    middle_y = 0.5 * (top + bottom)
    half_w = 0.5 * float(camera.frustum_width) if camera.frustum_width else half_h * width / height
    middle_x = float(camera.frustum_center)
    v = np.asarray(points, dtype=np.float64) - pos
    depth = v @ forward
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (near * (v @ right) / depth - middle_x) / half_w
        y = (near * (v @ up) / depth - middle_y) / half_h
    out = np.column_stack([(x + 1.0) * 0.5 * width, (1.0 - y) * 0.5 * height])
    out[depth <= near] = np.nan
    return out


@functools.lru_cache(maxsize=8)
def _disc(half: int) -> np.ndarray:
    """(k, 2) row, column offsets of the pixels within ``half`` of a centre pixel."""
    span = np.arange(-half, half + 1)
    rows, cols = np.meshgrid(span, span, indexing="ij")
    inside = rows * rows + cols * cols <= half * half
    return np.column_stack([rows[inside], cols[inside]])


def _stamp(image: np.ndarray, pixels: np.ndarray, colour: np.ndarray, half: int) -> None:
    """Paints a disc of radius ``half`` pixels around each pixel position (in place)."""
    height, width = image.shape[:2]
    centre = np.rint(pixels[:, ::-1]).astype(np.int64)  # (row, column)
    cells = (centre[:, None, :] + _disc(half)[None, :, :]).reshape(-1, 2)
    inside = (
        (cells[:, 0] >= 0) & (cells[:, 0] < height) & (cells[:, 1] >= 0) & (cells[:, 1] < width)
    )
    cells = cells[inside]
    image[cells[:, 0], cells[:, 1]] = colour


def draw_rings(
    image: np.ndarray, rings: Iterable[GroupRing], cameras: Sequence[object]
) -> np.ndarray:
    """Paints ``rings`` onto ``image`` (height, width, 3) uint8, in place; returns it.

    Each ring is projected through ``cameras`` (the scene's, as rendered) and drawn as a line
    of its colour and half-thickness, a disc per pixel of its length.
    """
    height, width = image.shape[:2]
    for ring in rings:
        outline = project(ring_points(ring), cameras, width, height)
        outline = outline[np.all(np.isfinite(outline), axis=1)]
        if len(outline) < 2:
            continue
        # Again with a point per pixel of the outline's length: a line without gaps.
        length = float(np.sum(np.hypot(*np.diff(outline, axis=0).T)))
        pixels = project(ring_points(ring, n=max(int(length), RING_POINTS)), cameras, width, height)
        pixels = pixels[np.all(np.isfinite(pixels), axis=1)]
        _stamp(image, pixels, np.asarray(ring.colour[:3], dtype=np.uint8), ring.width_px)
    return image

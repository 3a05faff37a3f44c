"""People and robots, frame by frame: shapes, facing arrows, trails, ids, the robot's view.

Entity tree (all under ``world``, z up, metres):

* ``world/people/bodies`` capsules standing at each person's body position (when no MuJoCo
  geometry is logged for them); ``world/people/labels`` a point over each head, labelled with the
  person's id; ``world/people/body_facing`` and ``world/people/head_facing`` arrows;
  ``world/people/trails`` the last seconds of each person's path.
* ``world/robot/...`` the same for the robot(s), plus ``world/robot/field_of_view``: the sensor's
  horizontal field of view, drawn from the head along the head's yaw.
* ``world/observed/people`` and ``world/observed/body_facing``: what the robot's sensor reports
  (with its noise and dropouts), when an observed stream is given.

Every entity has one row per frame on both timelines (empty where nobody is there), so nothing
lingers from an earlier frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import rerun as rr

from reform import Frame
from sim.recording import _colours
from sim.recording._columns import (
    FrameColumns,
    annotation_context,
    at_height,
    line_strips_column,
    send_rows,
    value_columns,
    vectors,
)
from sim.recording._timeline import Clock

__all__ = [
    "OBSERVED_ROOT",
    "PEOPLE_ROOT",
    "ROBOT_ROOT",
    "WORLD_ROOT",
    "KINECT_FIELD_OF_VIEW",
    "FieldOfView",
    "PersonIndex",
    "log_frames",
    "log_world_setup",
]

WORLD_ROOT = "world"
PEOPLE_ROOT = "world/people"
ROBOT_ROOT = "world/robot"
OBSERVED_ROOT = "world/observed"

HUMAN_HEIGHT_M = 1.70  # metres, top of the capsule
HUMAN_RADIUS_M = 0.20  # metres, shoulder half-width
ROBOT_HEIGHT_M = 1.20  # metres: a small humanoid guide robot
ROBOT_RADIUS_M = 0.25  # metres
BODY_ARROW_Z_M = 1.10  # metres: chest height of a person, where the body arrow starts
HEAD_ARROW_Z_M = 1.60  # metres: eye height of a person
ROBOT_BODY_ARROW_Z_M = 0.80  # metres
ROBOT_HEAD_Z_M = 1.10  # metres: the robot's head camera
LABEL_CLEARANCE_M = 0.15  # metres above the head
BODY_ARROW_M = 0.60  # metres, length of a body-facing arrow
HEAD_ARROW_M = 0.40  # metres
ARROW_RADIUS_M = 0.025  # metres
OBSERVED_Z_M = 1.30  # metres: height of an observed person's marker
OBSERVED_RADIUS_M = 0.09  # metres
TRAIL_S = 2.0  # seconds of path shown behind each person
TRAIL_POINTS = 8  # at most this many points per trail
TRAIL_Z_M = 0.03  # metres above the floor
TRAIL_RADIUS_M = 0.015  # metres
FIELD_OF_VIEW_ARC_POINTS = 9  # points on each arc of the drawn field of view
LABEL_RADIUS_M = 0.04  # metres


@dataclass(frozen=True)
class FieldOfView:
    """The robot sensor's horizontal field of view, as drawn (defaults: those of `sim.Sensor`,
    the Directions Robot's head sensor).

    Attributes:
        horizontal_deg: full horizontal opening angle, degrees, in (0, 360].
        min_range_m: nearest distance at which people are tracked, metres, >= 0.
        max_range_m: farthest distance, metres, > min_range_m.
    """

    horizontal_deg: float = 57.0
    min_range_m: float = 0.5
    max_range_m: float = 4.5

    def __post_init__(self) -> None:
        if not 0.0 < self.horizontal_deg <= 360.0:
            raise ValueError(f"horizontal_deg must be in (0, 360], got {self.horizontal_deg}")
        if not 0.0 <= self.min_range_m < self.max_range_m:
            raise ValueError(
                "ranges must satisfy 0 <= min_range_m < max_range_m, "
                f"got {self.min_range_m} and {self.max_range_m}"
            )

    @classmethod
    def of(cls, sensor: Any) -> FieldOfView:
        """The field of view of a `sim.Sensor` (its ``fov_deg``, ``min_range``, ``max_range``);
        None gives the default sensor's."""
        if sensor is None:
            return cls()
        return cls(
            horizontal_deg=float(sensor.fov_deg),
            min_range_m=float(sensor.min_range),
            max_range_m=float(sensor.max_range),
        )


@dataclass(frozen=True, eq=False)
class PersonIndex:
    """Class ids for person ids: every id of the run gets one, in increasing id order.

    Rerun's class ids are 16-bit, person ids are any integers; the annotation context logged
    at ``world`` turns a class id back into the person's label.

    Attributes:
        ids: (k,) int64 sorted person ids.
        robot: (k,) bool, True for ids that are robots.
    """

    ids: np.ndarray
    robot: np.ndarray

    @classmethod
    def of(cls, *streams: FrameColumns) -> PersonIndex:
        """Every id of the given (flattened) streams; an id is a robot if any row says so."""
        all_ids = np.concatenate([s.ids for s in streams]) if streams else np.zeros(0, np.int64)
        all_robot = np.concatenate([s.robot for s in streams]) if streams else np.zeros(0, bool)
        ids, inverse = np.unique(all_ids, return_inverse=True)
        if ids.size >= 65535:
            raise ValueError(f"a run may hold at most 65534 distinct person ids, got {ids.size}")
        robot = np.bincount(inverse, weights=all_robot, minlength=ids.size) > 0
        return cls(ids=ids.astype(np.int64), robot=robot)

    def class_ids(self, ids: np.ndarray) -> np.ndarray:
        """(n,) uint16 class id (1 + rank) of each person id."""
        return (np.searchsorted(self.ids, ids) + 1).astype(np.uint16)

    def label(self, person_id: int, robot: bool) -> str:
        return f"robot {person_id}" if robot else str(person_id)

    def annotation_context(self) -> list[rr.DescribedComponentBatch]:
        """The class of each person: label and colour (for ``rec.log``)."""
        return annotation_context(
            [
                (k + 1, self.label(pid, robot), _colours.ROBOT if robot else _colours.HUMAN)
                for k, (pid, robot) in enumerate(
                    zip(self.ids.tolist(), self.robot.tolist(), strict=True)
                )
            ]
        )


KINECT_FIELD_OF_VIEW = FieldOfView()  # the Directions Robot's head sensor: 57 deg, 0.5-4.5 m


def log_world_setup(rec: rr.RecordingStream) -> None:
    """The world's axes: right-handed, z up, metres (static)."""
    rec.log(WORLD_ROOT, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)


def log_frames(
    rec: rr.RecordingStream,
    frames: Sequence[Frame] | FrameColumns,
    *,
    observed: Sequence[Frame] | FrameColumns | None = None,
    clock: Clock | None = None,
    field_of_view: FieldOfView | None = KINECT_FIELD_OF_VIEW,
    shapes: bool = True,
    trail_s: float = TRAIL_S,
) -> Clock:
    """Logs people and robots of a finished run in bulk (one ``send_columns`` per entity).

    Args:
        rec: the recording stream.
        frames: the run's (world) frames, in time order, as ``reform.Frame`` objects or
            :class:`FrameColumns`.
        observed: what the robot's sensor reported, frames matched to ``frames`` by (sequence,
            time); may miss people (dropouts) and hold noisy poses.
        clock: the run's clock; default: the clock of ``frames``.
        field_of_view: drawn from each robot's head, or None for none.
        shapes: draw capsules for bodies; False when the MuJoCo geometry is logged instead.
        trail_s: seconds of path behind each person; 0 for no trails.

    Returns:
        The clock used.

    Raises:
        ValueError: if an observed frame matches no frame of the run, or ``trail_s`` < 0.
    """
    if trail_s < 0:
        raise ValueError(f"trail_s must be >= 0 seconds, got {trail_s}")
    flat = FrameColumns.coerce(frames)
    clock = Clock.from_columns(flat) if clock is None else clock
    rows = clock.rows_of_columns(flat)
    times = clock.columns(rows)
    seen = None if observed is None else FrameColumns.coerce(observed)
    people = PersonIndex.of(flat, *(() if seen is None else (seen,)))
    log_world_setup(rec)
    rec.log(WORLD_ROOT, people.annotation_context(), static=True)

    for root, mask, robot in (
        (PEOPLE_ROOT, ~flat.robot, False),
        (ROBOT_ROOT, flat.robot, True),
    ):
        if robot and not np.any(mask):
            continue
        part = flat.select(mask)
        person_ids = value_columns(part.counts, person_id=part.ids)
        _log_agents(rec, root, part, people, times, person_ids, robot=robot, shapes=shapes)
        if trail_s > 0:
            strips = _trails(part, clock, rows, people, trail_s=trail_s)
            send_rows(
                rec,
                f"{root}/trails",
                rr.LineStrips3D.from_fields(radii=[TRAIL_RADIUS_M], colors=[_colours.TRAIL]),
                times,
                [strips, *person_ids],
            )
        if robot and field_of_view is not None:
            _log_field_of_view(rec, part, times, field_of_view)
    if seen is not None:
        _log_observed(
            rec, seen, clock.columns(clock.rows_of_columns(seen, what="observed")), people
        )
    return clock


def _log_agents(
    rec: rr.RecordingStream,
    root: str,
    part: FrameColumns,
    people: PersonIndex,
    times: list[rr.TimeColumn],
    person_ids: list[rr.ComponentColumn],
    *,
    robot: bool,
    shapes: bool,
) -> None:
    height, radius = (ROBOT_HEIGHT_M, ROBOT_RADIUS_M) if robot else (HUMAN_HEIGHT_M, HUMAN_RADIUS_M)
    body_z, head_z = (
        (ROBOT_BODY_ARROW_Z_M, ROBOT_HEAD_Z_M) if robot else (BODY_ARROW_Z_M, HEAD_ARROW_Z_M)
    )
    n = part.ids.size
    class_ids = people.class_ids(part.ids)
    if shapes:
        send_rows(
            rec,
            f"{root}/bodies",
            rr.Capsules3D.from_fields(show_labels=False),
            times,
            [
                *rr.Capsules3D.columns(
                    lengths=np.full(n, height - 2.0 * radius, dtype=np.float32),
                    radii=np.full(n, radius, dtype=np.float32),
                    translations=at_height(part.position, radius),
                    class_ids=class_ids,
                ).partition(part.counts),
                *person_ids,
            ],
        )
    send_rows(
        rec,
        f"{root}/labels",
        rr.Points3D.from_fields(radii=[LABEL_RADIUS_M]),
        times,
        [
            *rr.Points3D.columns(
                positions=at_height(part.position, height + LABEL_CLEARANCE_M), class_ids=class_ids
            ).partition(part.counts),
            *person_ids,
        ],
    )
    _log_arrows(
        rec,
        f"{root}/body_facing",
        origins=at_height(part.position, body_z),
        yaw=part.yaw,
        length=BODY_ARROW_M,
        counts=part.counts,
        times=times,
        colour=_colours.BODY_FACING,
    )
    has_head = np.isfinite(part.head_yaw)
    _log_arrows(
        rec,
        f"{root}/head_facing",
        origins=at_height(part.head_position[has_head], head_z),
        yaw=part.head_yaw[has_head],
        length=HEAD_ARROW_M,
        counts=np.bincount(part.frame[has_head], minlength=part.counts.size),
        times=times,
        colour=_colours.HEAD_FACING,
    )


def _log_arrows(
    rec: rr.RecordingStream,
    entity: str,
    *,
    origins: np.ndarray,
    yaw: np.ndarray,
    length: float,
    counts: np.ndarray,
    times: list[rr.TimeColumn],
    colour: tuple[int, int, int, int],
) -> None:
    send_rows(
        rec,
        entity,
        rr.Arrows3D.from_fields(colors=[colour], radii=[ARROW_RADIUS_M]),
        times,
        rr.Arrows3D.columns(origins=origins, vectors=vectors(yaw, length)).partition(counts),
    )


def _trails(
    part: FrameColumns,
    clock: Clock,
    rows: np.ndarray,
    people: PersonIndex,
    *,
    trail_s: float,
) -> rr.ComponentColumn:
    """Each person's path over the last ``trail_s`` seconds of their sequence: one line strip
    per person and frame."""
    n_frames = part.counts.size
    sim_time = clock.sim_time[rows]
    # Dense (frame, person) table of the trail's points, as drawn (float32, at the trails'
    # height), NaN where the person is absent.
    n_slots = people.ids.size
    slot = np.searchsorted(people.ids, part.ids)
    dense = np.full((n_frames, n_slots, 3), np.nan, dtype=np.float32)
    dense[..., 2] = TRAIL_Z_M
    dense[part.frame, slot, :2] = part.position
    # Last frame before each frame at which each person was absent: trails do not jump gaps.
    absent = np.isnan(dense[..., 0])
    frame_index = np.arange(n_frames)[:, None]
    last_absent = np.maximum.accumulate(np.where(absent, frame_index, -1), axis=0)
    # First frame of each person-row's window: within trail_s, the same sequence, and after the
    # person's last absence.
    start = np.searchsorted(sim_time, sim_time - trail_s, side="left")
    segment = np.searchsorted(rows, clock.segment_start[rows], side="left")
    frame_of_row = part.frame
    start = np.maximum(start, segment)[frame_of_row]
    start = np.maximum(start, last_absent[frame_of_row, slot] + 1)
    span = frame_of_row - start  # frames back to the window's start
    # Up to TRAIL_POINTS frames evenly spread from the window's start to now, both included,
    # worked out once per span.
    spans = np.arange(int(span.max(initial=0)) + 1)
    n_points = np.minimum(TRAIL_POINTS, spans + 1)
    j = np.arange(TRAIL_POINTS)[None, :]
    offset = np.rint(j * spans[:, None] / np.maximum(n_points - 1, 1)[:, None]).astype(np.int64)
    strip_lengths = n_points[span]
    picked = (start[:, None] + offset[span]) * n_slots + slot[:, None]
    if np.any(strip_lengths < TRAIL_POINTS):
        picked = picked[j < strip_lengths[:, None]]
    picked = picked.reshape(-1)
    # One 12-byte item per point: taking whole points at once is several times faster.
    points = dense.reshape(-1, 3).view(np.dtype((np.void, 12))).reshape(-1)
    flat_points = np.take(points, picked).view(np.float32).reshape(-1, 3)
    return line_strips_column(flat_points, strip_lengths, part.counts)


def _log_field_of_view(
    rec: rr.RecordingStream, robots: FrameColumns, times: list[rr.TimeColumn], fov: FieldOfView
) -> None:
    """A wedge (far arc, near arc) from each robot's head along its head yaw (else body yaw)."""
    yaw = np.where(np.isfinite(robots.head_yaw), robots.head_yaw, robots.yaw)
    apex = np.where(np.isfinite(robots.head_position), robots.head_position, robots.position)
    half = math.radians(fov.horizontal_deg) / 2.0
    sweep = np.linspace(-half, half, FIELD_OF_VIEW_ARC_POINTS)
    angles = yaw[:, None] + np.concatenate([sweep, sweep[::-1], sweep[:1]])[None, :]
    radii = np.concatenate(
        [
            np.full(FIELD_OF_VIEW_ARC_POINTS, fov.max_range_m),
            np.full(FIELD_OF_VIEW_ARC_POINTS, fov.min_range_m),
            [fov.max_range_m],
        ]
    )
    x = apex[:, 0:1] + radii[None, :] * np.cos(angles)
    y = apex[:, 1:2] + radii[None, :] * np.sin(angles)
    points = np.stack([x, y, np.full_like(x, ROBOT_HEAD_Z_M)], axis=-1).reshape(-1, 3)
    send_rows(
        rec,
        f"{ROBOT_ROOT}/field_of_view",
        rr.LineStrips3D.from_fields(colors=[_colours.FIELD_OF_VIEW], radii=[0.01]),
        times,
        [line_strips_column(points, np.full(robots.ids.size, radii.size), robots.counts)],
    )


def _log_observed(
    rec: rr.RecordingStream,
    flat: FrameColumns,
    times: list[rr.TimeColumn],
    people: PersonIndex,
) -> None:
    humans = flat.select(~flat.robot)
    at = at_height(humans.position, OBSERVED_Z_M)
    send_rows(
        rec,
        f"{OBSERVED_ROOT}/people",
        rr.Points3D.from_fields(radii=[OBSERVED_RADIUS_M], colors=[_colours.OBSERVED]),
        times,
        [
            *rr.Points3D.columns(positions=at, class_ids=people.class_ids(humans.ids)).partition(
                humans.counts
            ),
            *value_columns(humans.counts, person_id=humans.ids),
        ],
    )
    _log_arrows(
        rec,
        f"{OBSERVED_ROOT}/body_facing",
        origins=at,
        yaw=humans.yaw,
        length=BODY_ARROW_M,
        counts=humans.counts,
        times=times,
        colour=_colours.OBSERVED,
    )

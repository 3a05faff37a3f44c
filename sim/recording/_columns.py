"""Flattening a run's frames into the columns that ``send_columns`` takes."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import rerun as rr

from reform import ROBOT, Frame

_POINT_TYPE = pa.list_(pa.field("item", pa.float32(), nullable=False), 3)
_LINE_STRIP_TYPE = pa.list_(pa.field("item", _POINT_TYPE, nullable=False))


@dataclass(frozen=True, eq=False)
class Flat:
    """Every person of every frame, one row each, frame by frame.

    Attributes:
        counts: (n_frames,) int64 people per frame.
        frame: (n,) int64 index of each row's frame in the input.
        ids: (n,) int64 person ids.
        robot: (n,) bool, True for robots.
        position: (n, 2) float64 metres.
        yaw: (n,) float64 radians.
        head_position: (n, 2) float64 metres, NaN where unknown.
        head_yaw: (n,) float64 radians, NaN where unknown.
    """

    counts: np.ndarray
    frame: np.ndarray
    ids: np.ndarray
    robot: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_position: np.ndarray
    head_yaw: np.ndarray

    @classmethod
    def of(cls, frames: Sequence[Frame]) -> Flat:
        counts = np.fromiter((f.n_people for f in frames), dtype=np.int64, count=len(frames))
        n = int(counts.sum())
        if n == 0:
            empty = np.zeros(0)
            return cls(
                counts=counts,
                frame=np.zeros(0, dtype=np.int64),
                ids=np.zeros(0, dtype=np.int64),
                robot=np.zeros(0, dtype=bool),
                position=np.zeros((0, 2)),
                yaw=empty,
                head_position=np.zeros((0, 2)),
                head_yaw=empty,
            )
        offsets = np.concatenate([[0], np.cumsum(counts)])
        head_position = np.full((n, 2), np.nan)
        head_yaw = np.full(n, np.nan)
        for k, frame in enumerate(frames):
            if frame.head_position is not None:
                head_position[offsets[k] : offsets[k + 1]] = frame.head_position
                head_yaw[offsets[k] : offsets[k + 1]] = frame.head_yaw
        kinds = np.array(list(itertools.chain.from_iterable(f.kinds for f in frames)))
        return cls(
            counts=counts,
            frame=np.repeat(np.arange(len(frames)), counts),
            ids=np.concatenate([f.ids for f in frames]),
            robot=kinds == ROBOT,
            position=np.concatenate([f.position for f in frames]),
            yaw=np.concatenate([f.yaw for f in frames]),
            head_position=head_position,
            head_yaw=head_yaw,
        )

    def select(self, mask: np.ndarray) -> Flat:
        """The rows where ``mask`` holds, with the per-frame counts recomputed."""
        return Flat(
            counts=np.bincount(self.frame[mask], minlength=self.counts.size).astype(np.int64),
            frame=self.frame[mask],
            ids=self.ids[mask],
            robot=self.robot[mask],
            position=self.position[mask],
            yaw=self.yaw[mask],
            head_position=self.head_position[mask],
            head_yaw=self.head_yaw[mask],
        )


class _ArrowBatch:
    """A ready-made Arrow array that ``rr.ComponentColumn`` can partition."""

    def __init__(self, array: pa.Array) -> None:
        self._array = array

    def as_arrow_array(self) -> pa.Array:
        return self._array


def value_columns(counts: np.ndarray, **values: np.ndarray) -> list[rr.ComponentColumn]:
    """Plain (archetype-less) components, e.g. ``person_id``, one value per instance.

    Args:
        counts: (n_frames,) instances per frame.
        values: component name -> (sum(counts),) integer array.
    """
    return [
        rr.ComponentColumn(name, _ArrowBatch(pa.array(_compact(np.asarray(array)))), lengths=counts)
        for name, array in values.items()
    ]


def _compact(array: np.ndarray) -> np.ndarray:
    """Integers as int32 when they fit (half the bytes of int64)."""
    info = np.iinfo(np.int32)
    if array.dtype.kind in "iu" and (
        array.size == 0 or (array.min() >= info.min and array.max() <= info.max)
    ):
        return array.astype(np.int32)
    return array


def line_strips_column(
    points: np.ndarray, strip_lengths: np.ndarray, frame_lengths: np.ndarray
) -> rr.ComponentColumn:
    """``LineStrips3D:strips`` for many frames at once, built straight in Arrow.

    Args:
        points: (m, 3) every strip's points, strip after strip.
        strip_lengths: (s,) points per strip; sums to m.
        frame_lengths: (n_frames,) strips per frame; sums to s.
    """
    values = pa.FixedSizeListArray.from_arrays(
        pa.array(np.ascontiguousarray(points, dtype=np.float32).reshape(-1), type=pa.float32()),
        type=_POINT_TYPE,
    )
    offsets = np.concatenate([[0], np.cumsum(strip_lengths)]).astype(np.int32)
    strips = pa.ListArray.from_arrays(
        pa.array(offsets, type=pa.int32()), values, type=_LINE_STRIP_TYPE
    )
    return rr.ComponentColumn(
        rr.LineStrips3D.descriptor_strips(), _ArrowBatch(strips), lengths=frame_lengths
    )


def at_height(position: np.ndarray, z: float | np.ndarray) -> np.ndarray:
    """(n, 3) ground-plane positions lifted to height ``z`` (metres)."""
    out = np.empty((position.shape[0], 3), dtype=np.float64)
    out[:, :2] = position
    out[:, 2] = z
    return out


def unit(yaw: np.ndarray) -> np.ndarray:
    """(n, 3) horizontal unit vectors pointing along ``yaw`` (radians)."""
    return np.column_stack([np.cos(yaw), np.sin(yaw), np.zeros_like(yaw)])

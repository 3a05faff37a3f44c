"""A run's frames as columns, and the columns that ``send_columns`` takes.

`FrameColumns` holds every person of every frame of a run in flat arrays (one row per person,
frame after frame) beside each frame's time, sequence and ground truth. Every logging function
works on it, so a run is read once, whatever number of entities it feeds; it is built from
``reform.Frame`` objects (`FrameColumns.of`) or straight from the simulator's pose blocks
(`FrameColumns.from_blocks`, without making a Frame per time step).
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa
import rerun as rr

from reform import ROBOT, Frame, FrameBlock, Group

__all__ = [
    "FrameColumns",
    "annotation_context",
    "at_height",
    "line_strips_column",
    "ragged_arange",
    "send_rows",
    "slices_equal",
    "value_columns",
    "vectors",
]

_POINT_TYPE = pa.list_(pa.field("item", pa.float32(), nullable=False), 3)
_LINE_STRIP_TYPE = pa.list_(pa.field("item", _POINT_TYPE, nullable=False))


@dataclass(frozen=True, eq=False)
class FrameColumns:
    """Every person of every frame of a run, one row each, frame by frame.

    Attributes:
        counts: (n_frames,) int64 people per frame.
        frame: (n,) int64 index of each row's frame.
        ids: (n,) int64 person ids.
        robot: (n,) bool, True for robots.
        position: (n, 2) float64 metres.
        yaw: (n,) float64 radians.
        head_position: (n, 2) float64 metres, NaN where unknown.
        head_yaw: (n,) float64 radians, NaN where unknown.
        time: (n_frames,) float64 each frame's time stamp, seconds.
        sequence: n_frames sequence names.
        groups: n_frames ground truths (groups of person ids), None where not annotated.
        frames: the ``reform.Frame`` objects the columns were made of, if any (detectors and
            ``reform.evaluate`` take frames).
    """

    counts: np.ndarray
    frame: np.ndarray
    ids: np.ndarray
    robot: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_position: np.ndarray
    head_yaw: np.ndarray
    time: np.ndarray
    sequence: tuple[str, ...]
    groups: tuple[tuple[Group, ...] | None, ...]
    frames: tuple[Frame, ...] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        n_frames = len(self.sequence)
        n = int(np.asarray(self.ids).shape[0])
        expected = {
            "counts": (n_frames,),
            "frame": (n,),
            "robot": (n,),
            "position": (n, 2),
            "yaw": (n,),
            "head_position": (n, 2),
            "head_yaw": (n,),
            "time": (n_frames,),
        }
        for name, shape in expected.items():
            found = np.shape(getattr(self, name))
            if found != shape:
                raise ValueError(f"FrameColumns.{name} must have shape {shape}, got {found}")
        if len(self.groups) != n_frames:
            raise ValueError(
                f"FrameColumns.groups must have {n_frames} entries, got {len(self.groups)}"
            )
        if int(np.sum(self.counts)) != n:
            raise ValueError(f"FrameColumns.counts must sum to {n} rows, got {np.sum(self.counts)}")

    @classmethod
    def of(cls, frames: Iterable[Frame]) -> FrameColumns:
        """The columns of ``frames`` (any iterable of ``reform.Frame``, e.g. a Dataset).

        Raises:
            ValueError: if an item is not a ``reform.Frame``.
        """
        frames = tuple(frames)
        if not all(isinstance(f, Frame) for f in frames):
            i = next(i for i, f in enumerate(frames) if not isinstance(f, Frame))
            raise ValueError(f"frames[{i}] must be a reform.Frame, got {type(frames[i]).__name__}")
        n_frames = len(frames)
        ids = [f.ids for f in frames]
        counts = np.fromiter(map(len, ids), dtype=np.int64, count=n_frames)
        robot_of: dict[tuple[str, ...], np.ndarray] = {}
        robot = []
        for kinds in (f.kinds for f in frames):
            mask = robot_of.get(kinds)
            if mask is None:
                mask = robot_of[kinds] = np.array([k == ROBOT for k in kinds], dtype=bool)
            robot.append(mask)
        head_position = [f.head_position for f in frames]
        head_yaw = [f.head_yaw for f in frames]
        if any(h is None for h in head_position):
            head_position = [
                np.full((c, 2), np.nan) if h is None else h
                for h, c in zip(head_position, counts.tolist(), strict=True)
            ]
            head_yaw = [
                np.full(c, np.nan) if h is None else h
                for h, c in zip(head_yaw, counts.tolist(), strict=True)
            ]
        return cls(
            counts=counts,
            frame=np.repeat(np.arange(n_frames, dtype=np.int64), counts),
            ids=_concatenate(ids, (0,), np.int64),
            robot=_concatenate(robot, (0,), bool),
            position=_concatenate([f.position for f in frames], (0, 2), np.float64),
            yaw=_concatenate([f.yaw for f in frames], (0,), np.float64),
            head_position=_concatenate(head_position, (0, 2), np.float64),
            head_yaw=_concatenate(head_yaw, (0,), np.float64),
            time=np.fromiter((f.time for f in frames), dtype=np.float64, count=n_frames),
            sequence=tuple(f.sequence for f in frames),
            groups=tuple(f.groups for f in frames),
            frames=frames,
        )

    @classmethod
    def from_blocks(cls, blocks: Iterable[FrameBlock]) -> FrameColumns:
        """The columns of frame blocks (`reform.FrameBlock`, as ``sim.episode.episode_blocks``
        yields them), equal to ``FrameColumns.of`` of the frames the blocks hold
        (``FrameBlock.frames()``), without making those frames.
        """
        parts: list[FrameColumns] = []
        for block in blocks:
            present = np.asarray(block.present, dtype=bool)
            rows, agents = np.nonzero(present)
            n_rows = present.shape[0]
            counts = present.sum(axis=1).astype(np.int64)
            robot = np.array([k == ROBOT for k in block.kinds], dtype=bool)
            parts.append(
                cls(
                    counts=counts,
                    frame=rows.astype(np.int64),
                    ids=np.asarray(block.ids, dtype=np.int64)[agents],
                    robot=robot[agents],
                    position=np.asarray(block.position, dtype=np.float64)[rows, agents],
                    yaw=np.asarray(block.yaw, dtype=np.float64)[rows, agents],
                    head_position=np.asarray(block.head_position, dtype=np.float64)[rows, agents],
                    head_yaw=np.asarray(block.head_yaw, dtype=np.float64)[rows, agents],
                    time=np.asarray(block.time, dtype=np.float64),
                    sequence=(str(block.sequence),) * n_rows,
                    groups=block.present_groups(),
                )
            )
        return cls.concatenate(parts)

    @classmethod
    def concatenate(cls, parts: Sequence[FrameColumns]) -> FrameColumns:
        """The frames of ``parts``, one after the other."""
        parts = list(parts)
        offsets = np.cumsum([0, *(len(p) for p in parts)])[:-1]
        frames = [p.frames for p in parts]
        return cls(
            counts=_concatenate([p.counts for p in parts], (0,), np.int64),
            frame=_concatenate(
                [p.frame + k for p, k in zip(parts, offsets.tolist(), strict=True)], (0,), np.int64
            ),
            ids=_concatenate([p.ids for p in parts], (0,), np.int64),
            robot=_concatenate([p.robot for p in parts], (0,), bool),
            position=_concatenate([p.position for p in parts], (0, 2), np.float64),
            yaw=_concatenate([p.yaw for p in parts], (0,), np.float64),
            head_position=_concatenate([p.head_position for p in parts], (0, 2), np.float64),
            head_yaw=_concatenate([p.head_yaw for p in parts], (0,), np.float64),
            time=_concatenate([p.time for p in parts], (0,), np.float64),
            sequence=tuple(s for p in parts for s in p.sequence),
            groups=tuple(g for p in parts for g in p.groups),
            frames=None if any(f is None for f in frames) else tuple(x for f in frames for x in f),  # type: ignore[union-attr]
        )

    @classmethod
    def coerce(cls, frames: Iterable[Frame] | FrameColumns) -> FrameColumns:
        """``frames`` if already columns, else their columns."""
        return frames if isinstance(frames, FrameColumns) else cls.of(frames)

    def __len__(self) -> int:
        return len(self.sequence)

    @functools.cached_property
    def starts(self) -> np.ndarray:
        """(n_frames + 1,) int64 first row of each frame, then the row count."""
        return np.concatenate([[0], np.cumsum(self.counts)]).astype(np.int64)

    @functools.cached_property
    def segment(self) -> np.ndarray:
        """(n_frames,) int64 index of each frame's run of consecutive frames of one sequence."""
        names = np.array(self.sequence, dtype=object)
        new = np.ones(names.size, dtype=bool)
        new[1:] = names[1:] != names[:-1]
        return np.cumsum(new) - 1

    @functools.cached_property
    def known_ids(self) -> np.ndarray:
        """(k,) int64 sorted distinct person ids of the run."""
        return np.unique(self.ids)

    def ids_of(self, index: int) -> np.ndarray:
        """(counts[index],) the person ids of frame ``index``."""
        return self.ids[self.starts[index] : self.starts[index + 1]]

    def describe(self, index: int) -> str:
        """``"sequence 's', time 1.5 s"`` of frame ``index``, for messages."""
        sequence = self.sequence[index]
        where = f"sequence {sequence!r}, " if sequence else ""
        return f"{where}time {self.time[index]:g} s"

    def same_people_as_previous(self) -> np.ndarray:
        """(n_frames,) bool: frame ``i`` holds the ids of frame ``i - 1``, in the same order."""
        n = len(self)
        out = np.zeros(n, dtype=bool)
        if n > 1:
            index = np.arange(1, n)
            out[1:] = slices_equal(self.ids, self.starts, index, index - 1)
        return out

    def select(self, mask: np.ndarray) -> FrameColumns:
        """The rows where ``mask`` holds, with the per-frame counts recomputed (frame times,
        sequences and ground truth unchanged)."""
        if np.all(mask):
            return self
        return FrameColumns(
            counts=np.bincount(self.frame[mask], minlength=len(self)).astype(np.int64),
            frame=self.frame[mask],
            ids=self.ids[mask],
            robot=self.robot[mask],
            position=self.position[mask],
            yaw=self.yaw[mask],
            head_position=self.head_position[mask],
            head_yaw=self.head_yaw[mask],
            time=self.time,
            sequence=self.sequence,
            groups=self.groups,
        )


def _concatenate(arrays: Sequence[np.ndarray], empty: tuple[int, ...], dtype: Any) -> np.ndarray:
    """``np.concatenate(arrays)`` as ``dtype``, of shape ``(n, *empty[1:])``; many small arrays
    of that dtype (one per frame) are joined as bytes, which is nearly twice as fast."""
    if not arrays:
        return np.zeros(empty, dtype=dtype)
    dtype = np.dtype(dtype)
    if {a.dtype for a in arrays} == {dtype}:
        try:
            joined = np.frombuffer(b"".join(arrays), dtype=dtype)
        except BufferError:  # an array that is not C-contiguous
            pass
        else:
            return joined.reshape((-1, *empty[1:]))
    return np.concatenate(arrays).astype(dtype, copy=False)


def ragged_arange(lengths: np.ndarray) -> np.ndarray:
    """``concatenate([arange(n) for n in lengths])``, vectorised: (sum(lengths),) int64."""
    lengths = np.asarray(lengths, dtype=np.int64)
    total = int(lengths.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    ends = np.cumsum(lengths)
    return np.arange(total, dtype=np.int64) - np.repeat(ends - lengths, lengths)


def slices_equal(
    values: np.ndarray, starts: np.ndarray, a: np.ndarray, b: np.ndarray
) -> np.ndarray:
    """(k,) bool: slice ``a[i]`` of ``values`` equals slice ``b[i]`` element by element.

    Args:
        values: (n, ...) the rows.
        starts: (m + 1,) int64 first row of each slice, then n.
        a, b: (k,) int64 slice indices to compare.
    """
    a = np.asarray(a, dtype=np.int64)
    b = np.asarray(b, dtype=np.int64)
    length = starts[a + 1] - starts[a]
    same = length == starts[b + 1] - starts[b]
    pick = np.flatnonzero(same)
    lengths = length[pick]
    owner = np.repeat(pick, lengths)
    local = ragged_arange(lengths)
    differ = values[starts[a[owner]] + local] != values[starts[b[owner]] + local]
    if differ.ndim > 1:
        differ = differ.reshape(differ.shape[0], -1).any(axis=1)
    same[owner[differ]] = False
    return same


class _ArrowBatch:
    """A ready-made Arrow array that ``rr.ComponentColumn`` can partition."""

    def __init__(self, array: pa.Array) -> None:
        self._array = array

    def as_arrow_array(self) -> pa.Array:
        return self._array


def annotation_context(
    classes: Sequence[tuple[int, str, tuple[int, int, int, int]]],
) -> list[rr.DescribedComponentBatch]:
    """An ``AnnotationContext`` of ``(class id, label, RGBA colour)`` classes, for ``rec.log``,
    built straight in Arrow (the archetype converts each class in Python, about 20 µs apiece).
    """
    list_type = rr.components.AnnotationContextBatch._ARROW_DATATYPE
    entry_type = list_type.value_type
    description_type = entry_type.field("class_description").type
    keypoints_type = description_type.field("keypoint_annotations").type
    connections_type = description_type.field("keypoint_connections").type
    n = len(classes)
    ids = pa.array([c[0] for c in classes], pa.uint16())
    rgba = np.array([c[2] for c in classes], dtype=np.uint32).reshape(n, 4)
    packed = (rgba[:, 0] << 24) | (rgba[:, 1] << 16) | (rgba[:, 2] << 8) | rgba[:, 3]
    info = pa.StructArray.from_arrays(
        [ids, pa.array([c[1] for c in classes], pa.utf8()), pa.array(packed, pa.uint32())],
        fields=list(description_type.field("info").type),
    )
    none = pa.array(np.zeros(n + 1, dtype=np.int32))
    description = pa.StructArray.from_arrays(
        [
            info,
            pa.ListArray.from_arrays(
                none, pa.array([], keypoints_type.value_type), type=keypoints_type
            ),
            pa.ListArray.from_arrays(
                none, pa.array([], connections_type.value_type), type=connections_type
            ),
        ],
        fields=list(description_type),
    )
    entries = pa.StructArray.from_arrays([ids, description], fields=list(entry_type))
    context = pa.ListArray.from_arrays(pa.array([0, n], pa.int32()), entries, type=list_type)
    return [
        rr.DescribedComponentBatch(_ArrowBatch(context), rr.AnnotationContext.descriptor_context())
    ]


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


def send_rows(
    rec: rr.RecordingStream,
    entity: str,
    defaults: Any,
    times: Sequence[rr.TimeColumn],
    columns: Iterable[Any],
) -> None:
    """Logs ``columns`` on ``entity``, one row per time, after its static ``defaults``.

    Args:
        rec: the recording stream.
        entity: the entity path.
        defaults: an archetype of the components every row shares (radii, colours, fill
            mode), logged once as static; None for none.
        times: the rows' time columns (``Clock.columns``).
        columns: the time-varying component columns.
    """
    if defaults is not None:
        rec.log(entity, defaults, static=True)
    rec.send_columns(entity, indexes=times, columns=columns, strict=True)


def at_height(position: np.ndarray, z: float) -> np.ndarray:
    """(n, 3) float32 ground-plane positions (metres) lifted to height ``z``, as Rerun stores
    them."""
    out = np.empty((position.shape[0], 3), dtype=np.float32)
    out[:, :2] = position
    out[:, 2] = z
    return out


def vectors(yaw: np.ndarray, length: float) -> np.ndarray:
    """(n, 3) float32 horizontal vectors of ``length`` (metres) along ``yaw`` (radians)."""
    out = np.empty((yaw.shape[0], 3), dtype=np.float32)
    out[:, 0] = np.cos(yaw) * length
    out[:, 1] = np.sin(yaw) * length
    out[:, 2] = 0.0
    return out

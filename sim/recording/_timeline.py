"""The recording's two timelines, and where each frame of a run sits on them.

Every time-varying entity is logged on both timelines: ``frame`` (a sequence: the frame's index
in the run) and ``sim_time`` (a duration: simulated seconds). A run may hold several sequences
(SALSA's two sessions); they are laid one after the other on ``sim_time``, each starting one
frame step after the previous one ends, so that the timeline never runs backwards.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import rerun as rr

from reform import Frame

__all__ = ["FRAME_TIMELINE", "SIM_TIME_TIMELINE", "Clock"]

FRAME_TIMELINE = "frame"  # sequence timeline: index of the frame in the run
SIM_TIME_TIMELINE = "sim_time"  # duration timeline: simulated seconds since the run started

# Frame times are matched to the microsecond: observed frames and detections find their world
# frame by (sequence, time) even after a round trip through float32 or Parquet.
_TIME_KEY_SCALE = 1_000_000  # keys per second
_DEFAULT_STEP_S = 1.0  # seconds: gap after a one-frame sequence


def _key(sequence: str, time: float) -> tuple[str, int]:
    return (sequence, round(time * _TIME_KEY_SCALE))


@dataclass(frozen=True, eq=False)
class Clock:
    """Maps the frames of a run to rows of the ``frame`` and ``sim_time`` timelines.

    Build it once from the run's (world) frames with :meth:`from_frames`; every other stream
    of the run (observed frames, detections, events) is placed by ``(sequence, time)``.

    Attributes:
        sequence: n_frames sequence names, one per frame.
        time: (n_frames,) float64 each frame's own time stamp, seconds.
        sim_time: (n_frames,) float64 position on the ``sim_time`` timeline, seconds;
            non-decreasing.
        segment_start: (n_frames,) int64 index of the first frame of each frame's sequence.
    """

    sequence: tuple[str, ...]
    time: np.ndarray
    sim_time: np.ndarray
    segment_start: np.ndarray
    _rows: dict[tuple[str, int], int]

    @classmethod
    def from_frames(cls, frames: Iterable[Frame]) -> Clock:
        """The clock of a run: frame ``i`` is row ``i`` of the ``frame`` timeline.

        Raises:
            ValueError: if time decreases within a sequence or a (sequence, time) repeats.
        """
        sequences: list[str] = []
        times: list[float] = []
        for i, frame in enumerate(frames):
            if not isinstance(frame, Frame):
                raise ValueError(f"frames[{i}] must be a reform.Frame, got {type(frame).__name__}")
            sequences.append(frame.sequence)
            times.append(frame.time)
        return cls.from_times(sequences, times)

    @classmethod
    def from_times(cls, sequences: Sequence[str], times: Sequence[float]) -> Clock:
        """The clock of frames given by their sequence names and time stamps (seconds)."""
        time = np.asarray(times, dtype=np.float64)
        if time.shape != (len(sequences),):
            raise ValueError(f"times must have shape ({len(sequences)},), got {time.shape}")
        n = time.size
        sim_time = np.zeros(n)
        segment_start = np.zeros(n, dtype=np.int64)
        rows: dict[tuple[str, int], int] = {}
        offset = 0.0
        start = 0
        for i in range(n):
            if i > 0 and sequences[i] != sequences[i - 1]:
                offset = sim_time[i - 1] + _step(time[start:i]) - time[i]
                start = i
            elif i > 0 and time[i] < time[i - 1]:
                raise ValueError(
                    f"frames[{i}] (sequence {sequences[i]!r}) has time {time[i]:g} s, before the "
                    f"previous frame's {time[i - 1]:g} s: frames must be in time order"
                )
            key = _key(sequences[i], float(time[i]))
            if key in rows:
                raise ValueError(
                    f"frames[{i}] repeats sequence {sequences[i]!r} time {time[i]:g} s "
                    f"(frames[{rows[key]}]): each frame needs its own time stamp"
                )
            rows[key] = i
            sim_time[i] = time[i] + offset
            segment_start[i] = start
        return cls(
            sequence=tuple(sequences),
            time=_readonly(time),
            sim_time=_readonly(sim_time),
            segment_start=_readonly(segment_start),
            _rows=rows,
        )

    def __len__(self) -> int:
        return int(self.time.size)

    def rows_of(self, frames: Iterable[Frame], *, what: str = "frames") -> np.ndarray:
        """(n,) int64 row of each frame, found by (sequence, time).

        Raises:
            ValueError: naming the first frame whose (sequence, time) is not in the run.
        """
        frames = list(frames)
        return self.rows_at([f.sequence for f in frames], [f.time for f in frames], what=what)

    def rows_at(
        self, sequences: Sequence[str], times: Sequence[float], *, what: str = "times"
    ) -> np.ndarray:
        """(n,) int64 row of the frame with each (sequence, time stamp in seconds).

        Raises:
            ValueError: naming the first (sequence, time) that is not a frame of the run.
        """
        rows = np.empty(len(times), dtype=np.int64)
        for i, (sequence, time) in enumerate(zip(sequences, times, strict=True)):
            row = self._rows.get(_key(sequence, float(time)))
            if row is None:
                raise ValueError(
                    f"{what}[{i}] (sequence {sequence!r}, time {float(time):g} s) matches no "
                    "frame of the run: expected the (sequence, time) of one of its frames"
                )
            rows[i] = row
        return rows

    def row_at(self, time: float, *, sequence: str | None = None) -> int:
        """Row of the last frame of ``sequence`` (default: the first) at or before ``time``."""
        if not len(self):
            raise ValueError("the run has no frames")
        name = self.sequence[0] if sequence is None else sequence
        members = np.flatnonzero(np.asarray(self.sequence, dtype=object) == name)
        if members.size == 0:
            raise ValueError(
                f"sequence {name!r} is not in the run (sequences {sorted(set(self.sequence))})"
            )
        k = int(np.searchsorted(self.time[members], time, side="right")) - 1
        return int(members[max(k, 0)])

    def sim_time_at(self, time: float, *, sequence: str | None = None) -> float:
        """Position of ``time`` (seconds, in ``sequence``) on the ``sim_time`` timeline."""
        row = self.row_at(time, sequence=sequence)
        return float(self.sim_time[row] + (time - self.time[row]))

    def columns(self, rows: np.ndarray | None = None) -> list[rr.TimeColumn]:
        """Time columns for ``send_columns``: ``frame`` and ``sim_time`` of the given rows."""
        rows = np.arange(len(self)) if rows is None else np.asarray(rows, dtype=np.int64)
        return [
            rr.TimeColumn(FRAME_TIMELINE, sequence=rows),
            rr.TimeColumn(SIM_TIME_TIMELINE, duration=self.sim_time[rows]),
        ]


def _step(times: np.ndarray) -> float:
    """Typical frame step of a sequence (median difference), seconds."""
    if times.size < 2:
        return _DEFAULT_STEP_S
    steps = np.diff(times)
    steps = steps[steps > 0]
    return float(np.median(steps)) if steps.size else _DEFAULT_STEP_S


def _readonly(array: np.ndarray) -> np.ndarray:
    array = np.array(array, copy=True)
    array.flags.writeable = False
    return array

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
import numpy.typing as npt
import rerun as rr

from reform import Frame
from sim.recording._columns import FrameColumns

__all__ = ["FRAME_TIMELINE", "SIM_TIME_TIMELINE", "Clock", "time_keys"]

FRAME_TIMELINE = "frame"  # sequence timeline: index of the frame in the run
SIM_TIME_TIMELINE = "sim_time"  # duration timeline: simulated seconds since the run started

# Frame times are matched to the microsecond: observed frames and detections find their world
# frame by (sequence, time) even after a round trip through float32 or Parquet.
TIME_KEY_SCALE = 1_000_000  # keys per second
_DEFAULT_STEP_S = 1.0  # seconds: gap after a one-frame sequence


def time_keys(times: npt.ArrayLike) -> np.ndarray:
    """(n,) int64 time stamps in microseconds (rounded half to even)."""
    return np.rint(np.asarray(times, dtype=np.float64) * TIME_KEY_SCALE).astype(np.int64)


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
    # sequence -> (sorted time keys, their rows)
    _tables: dict[str, tuple[np.ndarray, np.ndarray]]

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
    def from_columns(cls, columns: FrameColumns) -> Clock:
        """The clock of a run given as columns: frame ``i`` is row ``i``."""
        return cls.from_times(columns.sequence, columns.time)

    @classmethod
    def from_times(cls, sequences: Sequence[str], times: npt.ArrayLike) -> Clock:
        """The clock of frames given by their sequence names and time stamps (seconds)."""
        time = np.asarray(times, dtype=np.float64)
        sequences = tuple(sequences)
        if time.shape != (len(sequences),):
            raise ValueError(f"times must have shape ({len(sequences)},), got {time.shape}")
        n = time.size
        new = np.ones(n, dtype=bool)
        if n > 1:
            new[1:] = np.array(sequences[1:], dtype=object) != np.array(
                sequences[:-1], dtype=object
            )
        backwards = np.flatnonzero(~new[1:] & (np.diff(time) < 0)) + 1
        if backwards.size:
            i = int(backwards[0])
            raise ValueError(
                f"frames[{i}] (sequence {sequences[i]!r}) has time {time[i]:g} s, before the "
                f"previous frame's {time[i - 1]:g} s: frames must be in time order"
            )
        starts = np.flatnonzero(new)
        segment_start = starts[np.searchsorted(starts, np.arange(n), side="right") - 1]
        sim_time = time.copy()
        ends = np.append(starts[1:], n)
        offset = 0.0
        for k, (a, b) in enumerate(zip(starts.tolist(), ends.tolist(), strict=True)):
            if k:
                previous = sim_time[starts[k - 1] : a]
                offset = previous[-1] + _step(time[starts[k - 1] : a]) - time[a]
            sim_time[a:b] = time[a:b] + offset
        keys = time_keys(time)
        tables: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        names = np.array(sequences, dtype=object)
        for name in dict.fromkeys(sequences):
            rows = np.flatnonzero(names == name)
            order = np.argsort(keys[rows], kind="stable")
            sorted_keys, sorted_rows = keys[rows][order], rows[order]
            repeats = np.flatnonzero(np.diff(sorted_keys) == 0)
            if repeats.size:
                first, again = sorted(sorted_rows[[repeats[0], repeats[0] + 1]].tolist())
                raise ValueError(
                    f"frames[{again}] repeats sequence {name!r} time {time[again]:g} s "
                    f"(frames[{first}]): each frame needs its own time stamp"
                )
            tables[name] = (sorted_keys, sorted_rows)
        return cls(
            sequence=sequences,
            time=_readonly(time),
            sim_time=_readonly(sim_time),
            segment_start=_readonly(segment_start.astype(np.int64)),
            _tables=tables,
        )

    def __len__(self) -> int:
        return int(self.time.size)

    def rows_at(
        self, sequences: Sequence[str], times: npt.ArrayLike, *, what: str = "times"
    ) -> np.ndarray:
        """(n,) int64 row of the frame with each (sequence, time stamp in seconds).

        Raises:
            ValueError: naming the first (sequence, time) that is not a frame of the run.
        """
        sequences = tuple(sequences)
        time = np.asarray(times, dtype=np.float64).reshape(-1)
        if len(sequences) == len(self) and np.array_equal(time, self.time):
            if sequences == self.sequence:
                return np.arange(len(self), dtype=np.int64)  # the clock's own frames
        keys = time_keys(time)
        rows = np.full(keys.size, -1, dtype=np.int64)
        names = np.array(sequences, dtype=object)
        for name in dict.fromkeys(sequences):
            query = np.flatnonzero(names == name)
            if name not in self._tables:
                continue
            table_keys, table_rows = self._tables[name]
            at = np.minimum(np.searchsorted(table_keys, keys[query]), table_keys.size - 1)
            hit = table_keys[at] == keys[query]
            rows[query[hit]] = table_rows[at[hit]]
        missing = np.flatnonzero(rows < 0)
        if missing.size:
            i = int(missing[0])
            raise ValueError(
                f"{what}[{i}] (sequence {sequences[i]!r}, time {time[i]:g} s) matches no "
                "frame of the run: expected the (sequence, time) of one of its frames"
            )
        return rows

    def rows_of_columns(self, columns: FrameColumns, *, what: str = "frames") -> np.ndarray:
        """(n_frames,) int64 row of each frame of ``columns``, found by (sequence, time).

        Raises:
            ValueError: naming the first frame whose (sequence, time) is not in the run.
        """
        return self.rows_at(columns.sequence, columns.time, what=what)

    def row_at(self, time: float, *, sequence: str | None = None) -> int:
        """Row of the last frame of ``sequence`` (default: the first) at or before ``time``."""
        if not len(self):
            raise ValueError("the run has no frames")
        name = self.sequence[0] if sequence is None else sequence
        if name not in self._tables:
            raise ValueError(
                f"sequence {name!r} is not in the run (sequences {sorted(self._tables)})"
            )
        keys, rows = self._tables[name]
        k = int(np.searchsorted(keys, time_keys([time])[0], side="right")) - 1
        return int(rows[max(k, 0)])

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

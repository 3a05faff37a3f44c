"""Numbers over time: running precision / recall / F1 per detector, group counts, event log.

Entity tree:

* ``metrics/precision/<detector>``, ``metrics/recall/<detector>``, ``metrics/f1/<detector>``:
  the running scores at T = 2/3 after each annotated frame: P̄ and R̄ are the means of the
  per-frame precisions and recalls so far and F1 = 2·P̄·R̄/(P̄+R̄), the protocol of
  ``reform.metrics`` (the last value equals the evaluation's score).
* ``metrics/groups/truth`` and ``metrics/groups/<detector>``: F-formations per frame.
* ``events``: a text log of scenario events (turn starts, shuffles, eliminations, ...).
* ``events/truth`` and ``events/<detector>``: text logs of the group events
  (`reform.events`: groups forming, dissolving, merging, splitting, people joining and
  leaving) of the ground truth and of each detector's groups, at the frame of each event. One
  text-log view of ``events`` shows them all, each line under its entity.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import rerun as rr

from reform import T_TWO_THIRDS, Evaluation
from reform.events import DISSOLVES, FORMS, JOINS, LEAVES, MERGES, GroupEvent, partition_events
from sim.recording import _colours
from sim.recording._columns import FrameColumns, send_rows
from sim.recording._groups import TRUTH, LoggedGroups
from sim.recording._timeline import FRAME_TIMELINE, SIM_TIME_TIMELINE, Clock

__all__ = [
    "EVENTS_ENTITY",
    "METRICS_ROOT",
    "Event",
    "group_event_text",
    "log_events",
    "log_group_counts",
    "log_group_events",
    "log_running_scores",
    "stream_group_events",
]

METRICS_ROOT = "metrics"
EVENTS_ENTITY = "events"
SCORES = {"precision": "P̄", "recall": "R̄", "f1": "F1"}  # entity name -> label
INFO = "INFO"


@dataclass(frozen=True)
class Event:
    """Something that happened in a run, for the text log.

    Attributes:
        time: seconds, on the clock of ``sequence``.
        text: what happened, one line.
        level: a log level shown by the viewer (``"INFO"``, ``"WARN"``, ``"DEBUG"``, ...).
        sequence: the sequence (episode) it belongs to; None for the run's first.
    """

    time: float
    text: str
    level: str = INFO
    sequence: str | None = None

    @classmethod
    def coerce(cls, event: object, *, index: int = 0) -> Event:
        """An Event from an Event, a ``(time, text[, level])`` tuple, or any object with a
        ``time`` and a ``text`` (or ``kind`` and optional ``detail``) attribute."""
        if isinstance(event, Event):
            return event
        if isinstance(event, tuple) and len(event) in (2, 3):
            return cls(float(event[0]), str(event[1]), *(str(e) for e in event[2:]))
        time = getattr(event, "time", None)
        text = getattr(event, "text", None)
        if text is None and getattr(event, "kind", None) is not None:
            detail = getattr(event, "detail", None)
            text = f"{event.kind}: {detail}" if detail else str(event.kind)
        if time is None or text is None:
            raise ValueError(
                f"events[{index}] must be an Event, a (time, text[, level]) tuple or have "
                f"time and text (or kind) attributes, got {event!r}"
            )
        return cls(
            float(time),
            str(text),
            str(getattr(event, "level", INFO) or INFO),
            getattr(event, "sequence", None),
        )


def log_running_scores(
    rec: rr.RecordingStream, evaluations: Mapping[str, Evaluation], *, clock: Clock
) -> None:
    """Running P̄, R̄ and F1 (T = 2/3) per detector, one row per annotated frame.

    Args:
        rec: the recording stream.
        evaluations: detector name -> ``reform.evaluate(frames, predictions)`` (its frames'
            sequences and times place the rows).
        clock: the run's clock.
    """
    for index, (name, evaluation) in enumerate(evaluations.items()):
        scores = evaluation.at(T_TWO_THIRDS)
        count = np.arange(1, evaluation.n_frames + 1)
        precision = np.cumsum(scores.frame_precision) / count
        recall = np.cumsum(scores.frame_recall) / count
        total = precision + recall
        f1 = np.divide(2.0 * precision * recall, total, out=np.zeros_like(total), where=total > 0)
        times = clock.columns(
            clock.rows_at(evaluation.sequence, evaluation.time, what=f"{name} frames")
        )
        colour = _colours.series_colour(index)
        for (score, label), values in zip(SCORES.items(), (precision, recall, f1), strict=True):
            send_rows(
                rec,
                f"{METRICS_ROOT}/{score}/{name}",
                rr.SeriesLines(colors=[colour], names=[f"{name} {label}"]),
                times,
                rr.Scalars.columns(scalars=values),
            )


def log_group_counts(
    rec: rr.RecordingStream, trees: Mapping[str, LoggedGroups], *, clock: Clock
) -> None:
    """F-formations per frame for each group tree (truth first)."""
    for index, (name, tree) in enumerate(trees.items()):
        layout = tree.layout
        has_partition = layout.counts > 0
        rows = tree.rows[has_partition]
        colour = _colours.TRUTH_SERIES if name == TRUTH else _colours.series_colour(index - 1)
        send_rows(
            rec,
            f"{METRICS_ROOT}/groups/{name}",
            rr.SeriesLines(colors=[colour], names=[f"{name} F-formations"]),
            clock.columns(rows),
            rr.Scalars.columns(scalars=layout.group_counts[has_partition].astype(np.float64)),
        )


def stream_group_events(
    columns: FrameColumns, partitions: Sequence[Any] | None = None
) -> list[GroupEvent]:
    """The group events (`reform.partition_events`) of a stream's ground truth, or of
    ``partitions`` (one per frame of ``columns``, a detector's) on the frames the stream
    annotates (all its frames when it annotates none), as `reform.evaluate_events` takes them.
    A sequence with fewer than two such frames has none."""
    annotated = [groups is not None for groups in columns.groups]
    if partitions is None:
        chosen = list(columns.groups)
    elif any(annotated):
        chosen = [p if a else None for p, a in zip(partitions, annotated, strict=True)]
    else:
        chosen = list(partitions)
    if not chosen:
        return []
    return partition_events(chosen, times=columns.time, sequences=columns.sequence, skip_short=True)


def group_event_text(event: GroupEvent) -> str:
    """One line for the text log: ``4 joins group 1: {1, 2, 3, 4}``,
    ``groups 1 {1, 2} and 2 {3, 4} merge into group 1: {1, 2, 3, 4}``."""
    members = _names(event.members)
    if event.kind in (FORMS, DISSOLVES):
        return f"group {event.group} {event.kind}: {members}"
    if event.kind in (JOINS, LEAVES):
        return f"{event.person} {event.kind} group {event.group}: {members}"
    parts = " and ".join(
        f"{track} {_names(part)}"
        for track, part in zip(event.part_tracks, event.parts, strict=True)
    )
    if event.kind == MERGES:
        return f"groups {parts} merge into group {event.group}: {members}"
    return f"group {event.group} {members} splits into groups {parts}"


def log_group_events(
    rec: rr.RecordingStream, events: Sequence[GroupEvent], *, name: str, clock: Clock
) -> int:
    """Logs group events as the text log ``events/<name>``, each at its frame (found by its
    sequence and time); returns how many.

    Args:
        rec: the recording stream.
        events: `reform.GroupEvent` objects, in time order (`stream_group_events`).
        name: ``"truth"`` or the detector's name.
        clock: the run's clock.
    """
    if not events:
        return 0
    rows = clock.rows_at(
        [e.sequence for e in events], [e.time for e in events], what=f"{name} group events"
    )
    order = np.argsort(clock.sim_time[rows], kind="stable")
    rows = rows[order]
    send_rows(
        rec,
        f"{EVENTS_ENTITY}/{name}",
        None,
        clock.columns(rows),
        rr.TextLog.columns(
            text=[group_event_text(events[k]) for k in order.tolist()],
            level=[INFO] * len(events),
        ),
    )
    return len(events)


def _names(members: Iterable[int]) -> str:
    return "{" + ", ".join(str(m) for m in members) + "}"


def log_events(rec: rr.RecordingStream, events: Iterable[object], *, clock: Clock) -> int:
    """Logs events as one text log, in time order; returns how many.

    Args:
        rec: the recording stream.
        events: :class:`Event` objects, ``(time, text[, level])`` tuples, or objects with
            ``time`` and ``text`` (or ``kind``/``detail``) attributes; time in seconds of their
            sequence (default: the run's first), placed at the last frame at or before it.
        clock: the run's clock.
    """
    rows_, sim_times, texts, levels = [], [], [], []
    for i, raw in enumerate(events):
        event = Event.coerce(raw, index=i)
        rows_.append(clock.row_at(event.time, sequence=event.sequence))
        sim_times.append(clock.sim_time_at(event.time, sequence=event.sequence))
        texts.append(event.text)
        levels.append(event.level)
    if not texts:
        return 0
    order = np.argsort(np.asarray(sim_times), kind="stable")
    rows = np.asarray(rows_, dtype=np.int64)[order]
    send_rows(
        rec,
        EVENTS_ENTITY,
        None,
        [
            rr.TimeColumn(FRAME_TIMELINE, sequence=rows),
            rr.TimeColumn(SIM_TIME_TIMELINE, duration=np.asarray(sim_times)[order]),
        ],
        rr.TextLog.columns(
            text=[texts[k] for k in order.tolist()], level=[levels[k] for k in order.tolist()]
        ),
    )
    return len(texts)

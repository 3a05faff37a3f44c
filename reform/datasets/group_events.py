"""Group events stored with a dataset: a generated episode's shard carries its own.

``reform-sim generate`` stores each episode's ground-truth group events (`reform.events`: groups
forming, dissolving, merging, splitting, people joining and leaving) in its shard, under the
key :data:`GROUP_EVENTS_KEY` of the metadata the shard's header holds (the schema metadata
``reform_sim``, `reform.datasets.parquet`)::

    "group_events": {
        "tracks": 3,          # the episode's group tracks (ids 1..3)
        "events": [           # GroupEvent.to_json() of each event, in order
            {"kind": "joins", "sequence": "party-0", "time": 1.5, "frame": 3, "group": 1,
             "members": [1, 2, 4], "person": 4, "parts": [], "part_tracks": []},
            ...
        ]
    }

``frame`` is the frame's index in the shard (its ``frame`` column) and ``group`` the track,
counted from 1 within the episode. They are the events of the frames as the shard holds them
(after any annotation model), found by the rules of :func:`reform.group_events`; an episode with
fewer than two annotated frames has none (``"events": []``).

:func:`dataset_group_events` gives a dataset's events as one list, as if
``reform.group_events`` had been run on all its frames: frame indices and track ids run over the
whole dataset. Shards that store no events (written before they were stored, or by another
program) have theirs derived from their frames, so every dataset answers.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from reform.datasets.errors import DataFormatError
from reform.events import EVENT_KINDS, GroupEvent, _follow_partitions
from reform.frame import Dataset, Frame

__all__ = ["GROUP_EVENTS_KEY", "count_kinds", "dataset_group_events", "group_events_record"]

GROUP_EVENTS_KEY = "group_events"  # in a shard's metadata


def group_events_record(frames: Sequence[Frame] | None = None, **groups: Any) -> dict[str, Any]:
    """What a shard stores under :data:`GROUP_EVENTS_KEY`: the events of its frames and the
    number of group tracks.

    Args:
        frames: the shard's frames; or, without Frames, ``partitions=``, ``times=`` and
            ``sequences=`` as `reform.partition_events` takes them.

    Returns:
        ``{"tracks": n, "events": [event.to_json(), ...]}``.
    """
    events, tracks = _derive(frames, groups)
    return {"tracks": tracks, "events": [event.to_json() for event in events]}


def count_kinds(record: Mapping[str, Any]) -> dict[str, int]:
    """Events per kind (every kind of `reform.events.EVENT_KINDS`, zeros included) of a record
    made by :func:`group_events_record`."""
    counts = dict.fromkeys(EVENT_KINDS, 0)
    for event in record["events"]:
        counts[event["kind"]] += 1
    return counts


def _derive(frames: Sequence[Frame] | None, groups: Mapping[str, Any]) -> tuple[list, int]:
    """The events and the number of tracks of frames (or of partitions with their times and
    sequences); a sequence with fewer than two annotated frames has none."""
    if frames is not None:
        groups = {
            "partitions": [f.groups for f in frames],
            "times": [f.time for f in frames],
            "sequences": [f.sequence for f in frames],
        }
    if not len(groups["partitions"]):
        return [], 0
    followed = _follow_partitions(
        groups["partitions"],
        groups["times"],
        groups["sequences"],
        caller="group_events_record",
        skip_short=True,
    )  # partition_events and partition_tracks in one pass
    events = [event for f in followed for event in f.events]
    return events, len({span[0] for f in followed for span in f.spans})


def dataset_group_events(dataset: Dataset) -> list[GroupEvent]:
    """The group events of a dataset as read (`reform.datasets.read_parquet`): those its shards
    store, and for shards storing none those of their frames.

    The events are those :func:`reform.group_events` finds on ``dataset.frames``: ``frame``
    indexes ``dataset.frames`` and track ids count from 1 over the whole dataset; a sequence
    with fewer than two annotated frames has none (where ``group_events`` refuses it).

    Raises:
        DataFormatError: a shard's stored events are malformed or do not fit its frames
            (naming the shard and what was expected).
    """
    out: list[GroupEvent] = []
    start = tracks = 0
    for metadata, n, where in _pieces(dataset):
        frames = dataset.frames[start : start + n]
        stored = metadata.get(GROUP_EVENTS_KEY) if isinstance(metadata, Mapping) else None
        if stored is None:
            events, count = _derive(frames, {})
        else:
            events, count = _stored(stored, frames, where)
        out += [_shifted(event, start, tracks) for event in events]
        start += n
        tracks += count
    return out


def _pieces(dataset: Dataset) -> list[tuple[Any, int, str | Path]]:
    """Each shard of a dataset read from a folder (its metadata, its frame count, its path), or
    the whole dataset as one piece."""
    shards = dataset.metadata.get("shards")
    if isinstance(shards, (list, tuple)) and all(
        isinstance(s, Mapping) and isinstance(s.get("frames"), int) for s in shards
    ):
        if sum(s["frames"] for s in shards) == len(dataset.frames):
            folder = Path(dataset.source or ".")
            return [
                (s.get("metadata"), s["frames"], folder / str(s.get("path", ""))) for s in shards
            ]
    return [(dataset.metadata, len(dataset.frames), dataset.source or dataset.name)]


def _stored(record: Any, frames: Sequence[Frame], where: str | Path) -> tuple[list, int]:
    """The events and track count a shard stores, checked against its frames."""
    field = f"metadata.{GROUP_EVENTS_KEY}"
    if not (
        isinstance(record, Mapping)
        and isinstance(record.get("events"), list)
        and isinstance(record.get("tracks"), int)
        and not isinstance(record.get("tracks"), bool)
    ):
        raise DataFormatError(
            where,
            None,
            field,
            "an object with 'tracks' (an int) and 'events' (a list)",
            repr(record),
        )
    sequences = {f.sequence for f in frames}
    events = []
    for k, raw in enumerate(record["events"]):
        try:
            event = GroupEvent.from_json(raw)
        except ValueError as exc:
            raise DataFormatError(
                where,
                f"event {k}",
                field,
                "a group event as GroupEvent.to_json writes it",
                str(exc),
            ) from None
        if not (0 <= event.frame < len(frames)) or event.sequence not in sequences:
            raise DataFormatError(
                where,
                f"event {k}",
                field,
                f"a frame index below {len(frames)} of the shard's sequences {sorted(sequences)}",
                f"frame {event.frame} of sequence {event.sequence!r}",
            )
        tracks = (event.group, *event.part_tracks)
        if min(tracks) < 1 or max(tracks) > record["tracks"]:
            raise DataFormatError(
                where,
                f"event {k}",
                field,
                f"track ids from 1 to {record['tracks']} (its 'tracks')",
                str(tracks),
            )
        events.append(event)
    return events, record["tracks"]


def _shifted(event: GroupEvent, frames: int, tracks: int) -> GroupEvent:
    """``event`` with its frame index and track ids moved by ``frames`` and ``tracks``."""
    if not frames and not tracks:
        return event
    return dataclasses.replace(
        event,
        frame=event.frame + frames,
        group=event.group + tracks,
        part_tracks=tuple(t + tracks for t in event.part_tracks),
    )

"""One-call entry points: a whole episode, or a detector evaluation, into one recording."""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import rerun as rr

from reform import Evaluation, Frame, Group, GroupEvent
from reform.perturb import restrict_groups
from sim.recording._blueprint import default_blueprint
from sim.recording._columns import FrameColumns
from sim.recording._dataset_views import log_characterisation, log_pair_scatter, pair_scatter_data
from sim.recording._frames import KINECT_FIELD_OF_VIEW, FieldOfView, log_frames
from sim.recording._groups import TRUTH, GroupLayout, log_groups
from sim.recording._metrics import (
    log_events,
    log_group_counts,
    log_group_events,
    log_running_scores,
    stream_group_events,
)
from sim.recording._program import rerun_in_this_shell
from sim.recording._scene import (
    BodyPoses,
    CameraImages,
    log_body_poses,
    log_camera_images,
    log_model,
    log_room,
    person_bodies,
    room_bounds,
)
from sim.recording._stream import open_recording, recording_id
from sim.recording._target import RecordingTarget, target_from_args
from sim.recording._timeline import Clock
from sim.sizing import recording_disk

__all__ = [
    "CROWD_PEOPLE",
    "Recorded",
    "record_episode",
    "record_evaluation",
    "record_from_args",
]

# People: a recording of more leaves the people's MuJoCo bodies out of the model's geometry and
# draws everyone batched (`log_frames`' capsules): one entity per body stays usable for a party
# (18 people: 54 bodies) but not for a concourse (1,000 people: 9,000 entities, 40 MB for 10 s).
CROWD_PEOPLE = 100

Partition = Sequence[Group]


@dataclass(frozen=True, eq=False)
class Recorded:
    """What a one-call recording wrote.

    Attributes:
        recording_id: the recording's id (deterministic in name and seed).
        n_frames: frames on the ``frame`` timeline.
        evaluations: detector name -> its evaluation (T = 2/3 and 1) where ground truth existed.
    """

    recording_id: str
    n_frames: int
    evaluations: Mapping[str, Evaluation] = field(default_factory=dict, repr=False)


def _check_names(detections: Mapping[str, Any]) -> None:
    for name in detections:
        if not name or "/" in name or name == TRUTH:
            raise ValueError(
                f"detector names must be non-empty, without '/', and not {TRUTH!r}; got {name!r}"
            )


def _with_truth(observed: FrameColumns, world: FrameColumns, clock: Clock) -> FrameColumns:
    """Observed frames without ground truth get the world's, restricted to who was observed."""
    missing = [f for f, groups in enumerate(observed.groups) if groups is None]
    if not missing:
        return observed

    world_truth = dict(zip(clock.rows_of_columns(world).tolist(), world.groups, strict=True))
    rows = clock.rows_of_columns(observed, what="observed")
    groups = list(observed.groups)
    for f in missing:
        groups[f] = restrict_groups(world_truth.get(int(rows[f])), set(observed.ids_of(f).tolist()))
    frames = observed.frames
    if frames is not None:
        frames = tuple(
            frame if frame.groups is groups[f] else frame.replace(groups=groups[f])
            for f, frame in enumerate(frames)
        )
    return dataclasses.replace(observed, groups=tuple(groups), frames=frames)


def _most_fformations(partitions: Iterable[Partition | None]) -> int:
    """The most F-formations (groups of two or more) of any one partition."""
    best, last = 0, None
    for partition in partitions:
        if partition is None or partition is last:
            continue
        last = partition
        best = max(best, sum(1 for group in partition if len(group) >= 2))
    return best


def _group_event_logs(
    world: FrameColumns, detected_on: FrameColumns, detections: Mapping[str, Sequence[Partition]]
) -> dict[str, list[GroupEvent]]:
    """The group events of the truth (where ``world`` is annotated) and of each detector, by
    name. A detector whose partitions cannot be read is left out here: `log_groups` names its
    mistake before anything is logged from them."""
    found = {}
    if any(groups is not None for groups in world.groups):
        found[TRUTH] = stream_group_events(world)
    for name, partitions in detections.items():
        try:
            found[name] = stream_group_events(detected_on, list(partitions))
        except (TypeError, ValueError):
            continue
    return found


def _run_blueprint(
    world: FrameColumns,
    detections: Mapping[str, Sequence[Partition]],
    events: Sequence[object],
    group_event_logs: Mapping[str, Sequence[GroupEvent]],
    **views: Any,
) -> rr.blueprint.Blueprint:
    """The default layout of a run recorded by `_log_groups_and_scores`: panels only for what
    it logs (scores with ground truth and detectors, group counts for any group tree, events
    given or group events found), the counts plot's range holding every count."""
    annotated = any(groups is not None for groups in world.groups)
    truth = GroupLayout.truth(world) if annotated else None
    counts = [int(truth.group_counts.max(initial=0))] if truth is not None else []
    counts += [_most_fformations(partitions) for partitions in detections.values()]
    return default_blueprint(
        scores=annotated and bool(detections),
        max_groups=max(counts) if counts else None,
        events=bool(events) or any(group_event_logs.values()),
        **views,
    )


def _log_groups_and_scores(
    rec: rr.RecordingStream,
    world: FrameColumns,
    detected_on: FrameColumns,
    detections: Mapping[str, Sequence[Partition]],
    evaluations: Mapping[str, Evaluation] | None,
    events: Iterable[object],
    group_event_logs: Mapping[str, Sequence[GroupEvent]],
    *,
    clock: Clock,
) -> dict[str, Evaluation]:
    """The truth tree (where ``world`` is annotated), one tree per detector (on
    ``detected_on``), group counts, running scores, ``events``, and the group events of the
    truth and of each detector; returns the detectors' evaluations."""
    annotated = any(groups is not None for groups in world.groups)
    truth = log_groups(rec, world, name=TRUTH, clock=clock) if annotated else None
    trees = {} if truth is None else {TRUTH: truth}
    for index, (name, partitions) in enumerate(detections.items()):
        # Groups no true group matches take tracks no earlier tree used: their own colours.
        first = 1 + max((int(t.tracks.max(initial=0)) for t in trees.values()), default=0)
        trees[name] = log_groups(
            rec,
            detected_on,
            list(partitions),
            name=name,
            clock=clock,
            evaluation=(evaluations or {}).get(name),
            truth=truth,
            layer=index + 1,
            first_track=first,
        )
    scored = {
        name: tree.evaluation
        for name, tree in trees.items()
        if name != TRUTH and tree.evaluation is not None
    }
    log_group_counts(rec, trees, clock=clock)
    log_running_scores(rec, scored, clock=clock)
    log_events(rec, events, clock=clock)
    for name, found in group_event_logs.items():  # the truth's, then each detector's
        log_group_events(rec, found, name=name, clock=clock)
    return scored


def record_episode(
    target: RecordingTarget | str | os.PathLike[str],
    world_frames: Iterable[Frame] | FrameColumns,
    *,
    observed: Iterable[Frame] | FrameColumns | None = None,
    detections: Mapping[str, Sequence[Partition]] | None = None,
    evaluations: Mapping[str, Evaluation] | None = None,
    events: Iterable[object] | None = None,
    model: Any = None,
    body_poses: BodyPoses | None = None,
    cameras: Iterable[CameraImages] = (),
    seed: int | None = None,
    name: str | None = None,
    field_of_view: FieldOfView | None = KINECT_FIELD_OF_VIEW,
) -> Recorded:
    """Records a finished episode: scene, people, robot, groups, detections, scores, events.

    Args:
        target: a ``.rrd`` path, or a :class:`RecordingTarget` (file, viewer, server).
        world_frames: the episode's ground-truth frames, in time order (any iterable of
            ``reform.Frame``), or their :class:`FrameColumns` (e.g.
            ``FrameColumns.from_blocks(sim.episode.episode_blocks(...))``).
        observed: the robot's observed frames (noise, dropouts), matched to the world frames by
            (sequence, time). Observed frames without ground truth are scored against the
            world's groups restricted to the people observed.
        detections: detector name (``"reform"``, ``"gcff"``) -> one full partition per frame of
            the stream the detector saw: ``observed`` when given, else ``world_frames``.
        evaluations: detector name -> ``reform.evaluate(stream, partitions)``, if already
            computed; otherwise computed here where the stream carries ground truth.
        events: scenario events (:class:`Event`, ``(time, text[, level])`` tuples or objects
            with ``time`` and ``text``/``kind``), logged on ``events``; the group events of the
            ground truth and of each detector (`reform.events`) go to ``events/truth`` and
            ``events/<detector>``.
        model: the compiled ``mujoco.MjModel`` of the scene: its geometry is drawn (static)
            and, with ``body_poses``, moves per frame; people are then not drawn as capsules.
            With more than `CROWD_PEOPLE` people, the level of detail drops: their bodies are
            left out of the model's geometry and everyone is drawn as capsules, one batched
            entity for all people (``world/people/bodies``).
        body_poses: the bodies' poses per frame (needs ``model``).
        cameras: rendered camera images (the robot's head camera), when rendering is on.
        seed: the episode's seed (with ``name``, it fixes the recording id).
        name: the run's name; default: the first frame's sequence, else ``"episode"``.
        field_of_view: the robot sensor's field of view to draw, or None.

    Returns:
        The recording id, frame count and the detectors' evaluations.
    """
    world = FrameColumns.coerce(world_frames)
    if not len(world):
        raise ValueError("world_frames must hold at least one frame, got none")
    if body_poses is not None and model is None:
        raise ValueError("body_poses needs the model they belong to: pass model=")
    detections = dict(detections or {})
    _check_names(detections)
    clock = Clock.from_columns(world)
    seen = None if observed is None else _with_truth(FrameColumns.coerce(observed), world, clock)
    detected_on = seen if seen is not None else world
    name = name or world.sequence[0] or "episode"
    cameras = tuple(cameras)
    events = tuple(events or ())
    bounds = room_bounds(world)
    found = _group_event_logs(world, detected_on, detections)
    blueprint = _run_blueprint(
        world, detections, events, found, bounds=bounds, cameras=tuple(c.name for c in cameras)
    )
    bodies = None  # every body of the model
    if model is not None and len(np.unique(world.ids[~world.robot])) > CROWD_PEOPLE:
        bodies = np.setdiff1d(np.arange(model.nbody), person_bodies(model))
    expected = recording_disk(
        max(1, round(float(np.mean(world.counts)))),
        len(world),
        view="truth" if seen is None else "robot",
        model=model is not None and bodies is None,
    )
    with open_recording(
        target, name=name, seed=seed, blueprint=blueprint, expected_bytes=expected
    ) as rec:
        log_frames(
            rec,
            world,
            observed=seen,
            clock=clock,
            field_of_view=field_of_view,
            shapes=body_poses is None or bodies is not None,
        )
        if model is not None:
            log_model(rec, model, static_poses=body_poses is None, bodies=bodies)
            if body_poses is not None:
                log_body_poses(rec, model, body_poses, clock=clock, bodies=bodies)
        else:
            log_room(rec, bounds)
        for camera in cameras:
            log_camera_images(rec, camera, clock=clock)
        scored = _log_groups_and_scores(
            rec, world, detected_on, detections, evaluations, events, found, clock=clock
        )
    return Recorded(
        recording_id=recording_id(name, seed=seed), n_frames=len(world), evaluations=scored
    )


def record_evaluation(
    target: RecordingTarget | str | os.PathLike[str],
    frames: Iterable[Frame] | FrameColumns,
    predictions_by_detector: Mapping[str, Sequence[Partition]],
    evaluations: Mapping[str, Evaluation] | None = None,
    *,
    name: str = "evaluation",
    dataset: str | None = None,
    seed: int | None = None,
    classifier: Any = None,
    dataset_views: bool = True,
) -> Recorded:
    """Records detectors run on a dataset: people, groups and mistakes, running scores, and the
    dataset's characterisation and pair scatter.

    Args:
        target: a ``.rrd`` path, or a :class:`RecordingTarget`.
        frames: the frames the detectors ran on, in time order (a Dataset works), or their
            :class:`FrameColumns` made with ``FrameColumns.of``.
        predictions_by_detector: detector name -> one full partition per frame.
        evaluations: detector name -> ``reform.evaluate(frames, predictions)``, if already
            computed; otherwise computed here where the frames carry ground truth.
        name: the run's name (with ``seed``, it fixes the recording id).
        dataset: the dataset's name for the dataset views; default: the first frame's sequence.
        seed: the run's seed, if any.
        classifier: a fitted pair classifier (``predict_proba`` on (distance, effort angle)) or
            a callable giving P(together), for the decision regions; None for none.
        dataset_views: log Tightness/Symmetry by group size and the pair scatter.

    Returns:
        The recording id, frame count and the detectors' evaluations.
    """
    columns = FrameColumns.coerce(frames)
    if not len(columns):
        raise ValueError("frames must hold at least one frame, got none")
    predictions = dict(predictions_by_detector)
    _check_names(predictions)
    annotated = any(groups is not None for groups in columns.groups)
    dataset = dataset or columns.sequence[0] or "dataset"
    views = (dataset,) if dataset_views and annotated else ()
    if views and columns.frames is None:
        raise ValueError("dataset views need the frames: pass reform.Frame objects, not columns")
    bounds = room_bounds(columns)
    found = _group_event_logs(columns, columns, predictions)
    blueprint = _run_blueprint(
        columns, predictions, (), found, bounds=bounds, characterisation=views, pairs=views
    )
    with open_recording(target, name=name, seed=seed, blueprint=blueprint) as rec:
        clock = log_frames(rec, columns, field_of_view=None)
        log_room(rec, bounds)
        scored = _log_groups_and_scores(
            rec, columns, columns, predictions, evaluations, (), found, clock=clock
        )
        if views:
            log_characterisation(rec, columns.frames, name=dataset)
            distance, effort, label = pair_scatter_data(columns.frames)
            log_pair_scatter(rec, distance, effort, label, name=dataset, classifier=classifier)
    return Recorded(
        recording_id=recording_id(name, seed=seed), n_frames=len(columns), evaluations=scored
    )


def record_from_args(
    args: argparse.Namespace,
    frames: Iterable[Frame],
    predictions_by_detector: Mapping[str, Sequence[Partition]],
    evaluations: Mapping[str, Evaluation] | None = None,
    *,
    name: str,
    dataset: str | None = None,
) -> Recorded | None:
    """For a command with :func:`add_recording_arguments`: records the run where the flags say
    (``--save``, ``--connect``, ``--serve``); does nothing when none is given.

    Args:
        args: the parsed command line.
        frames, predictions_by_detector, evaluations, dataset: as for :func:`record_evaluation`.
        name: the run's name, e.g. ``"evaluate-majority-salsa"``.

    Returns:
        What was recorded, or None.
    """
    target = target_from_args(args)
    if target is None:
        return None
    recorded = record_evaluation(
        target, frames, predictions_by_detector, evaluations, name=name, dataset=dataset
    )
    if target.save is not None:
        rerun = rerun_in_this_shell()
        print(f"wrote {target.save} (open it with `{rerun} {target.save}`)", file=sys.stderr)
    return recorded

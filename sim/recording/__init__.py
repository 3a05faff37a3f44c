"""Rerun recordings of runs: every simulation, detection and evaluation inspectable offline.

One recording per run (application id ``reform-sim``, recording id from the run's name and
seed), saved as an ``.rrd`` file that ``rerun run.rrd`` opens. Finished runs are logged in bulk
(``send_columns``), on two timelines: ``frame`` and ``sim_time``.

One call records a whole run::

    from sim.recording import record_episode, record_evaluation

    record_episode("run.rrd", world_frames, observed=observed, detections={"reform": parts},
                   events=events, model=model, seed=7)
    record_evaluation("salsa.rrd", frames, {"reform": predictions}, {"reform": evaluation})

or, piece by piece, open a stream and pass it to the ``log_*`` functions::

    with open_recording("run.rrd", name="babble", seed=7, blueprint=default_blueprint()) as rec:
        columns = FrameColumns.of(frames)  # read the frames once
        clock = log_frames(rec, columns)
        truth = log_groups(rec, columns, clock=clock)
        log_groups(rec, columns, predictions, name="reform", clock=clock, truth=truth)

Logging is columnar: a run's frames are read once into :class:`FrameColumns` (every person of
every frame in flat arrays), partitions are laid out once per distinct partition, and group
colours, events and mistakes are worked out only where the partitions change. The simulator's
pose blocks can be recorded without making Frames: ``record_episode(path,
FrameColumns.from_blocks(sim.episode.episode_blocks(...)))``.

Entity tree: ``world/`` (room, MuJoCo model, people, robot, observed people, groups per source
with mistakes), ``camera/`` (head-camera images), ``metrics/`` (running scores, group counts),
``events``, ``dataset/`` (characterisation, pair scatter, stress curves).
"""

from __future__ import annotations

from sim.recording._blueprint import default_blueprint
from sim.recording._columns import FrameColumns
from sim.recording._dataset_views import (
    DATASET_ROOT,
    log_characterisation,
    log_pair_scatter,
    log_stress_curves,
    pair_scatter_data,
)
from sim.recording._frames import (
    KINECT_FIELD_OF_VIEW,
    OBSERVED_ROOT,
    PEOPLE_ROOT,
    ROBOT_ROOT,
    WORLD_ROOT,
    FieldOfView,
    log_frames,
    log_world_setup,
)
from sim.recording._groups import GROUPS_ROOT, TRUTH, LoggedGroups, evaluate_detector, log_groups
from sim.recording._metrics import (
    EVENTS_ENTITY,
    METRICS_ROOT,
    Event,
    group_events,
    log_events,
    log_group_counts,
    log_running_scores,
)
from sim.recording._record import Recorded, record_episode, record_evaluation, record_from_args
from sim.recording._scene import (
    CAMERA_ROOT,
    MODEL_ROOT,
    ROOM_ROOT,
    BodyPoses,
    CameraImages,
    body_entity,
    log_body_poses,
    log_camera_images,
    log_model,
    log_room,
    room_bounds,
)
from sim.recording._stream import (
    APPLICATION_ID,
    RecordingTarget,
    add_recording_arguments,
    open_recording,
    recording_id,
    target_from_args,
)
from sim.recording._timeline import FRAME_TIMELINE, SIM_TIME_TIMELINE, Clock

__all__ = [
    "APPLICATION_ID",
    "CAMERA_ROOT",
    "DATASET_ROOT",
    "EVENTS_ENTITY",
    "FRAME_TIMELINE",
    "GROUPS_ROOT",
    "KINECT_FIELD_OF_VIEW",
    "METRICS_ROOT",
    "MODEL_ROOT",
    "OBSERVED_ROOT",
    "PEOPLE_ROOT",
    "ROBOT_ROOT",
    "ROOM_ROOT",
    "SIM_TIME_TIMELINE",
    "TRUTH",
    "WORLD_ROOT",
    "BodyPoses",
    "CameraImages",
    "Clock",
    "Event",
    "FieldOfView",
    "FrameColumns",
    "LoggedGroups",
    "Recorded",
    "RecordingTarget",
    "add_recording_arguments",
    "body_entity",
    "default_blueprint",
    "evaluate_detector",
    "group_events",
    "log_body_poses",
    "log_camera_images",
    "log_characterisation",
    "log_events",
    "log_frames",
    "log_group_counts",
    "log_groups",
    "log_model",
    "log_pair_scatter",
    "log_room",
    "log_running_scores",
    "log_stress_curves",
    "log_world_setup",
    "open_recording",
    "pair_scatter_data",
    "recording_id",
    "record_episode",
    "record_evaluation",
    "record_from_args",
    "room_bounds",
    "target_from_args",
]

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

A viewer the project starts itself (``--serve``'s web viewer, the Gymnasium environments'
window, the tests' servers) is the Rerun program run through :func:`viewer_command`, listening
on 127.0.0.1, and stopped with :func:`stop_viewer`.

Entity tree: ``world/`` (room, MuJoCo model, people, robot, observed people, groups per source
with mistakes), ``camera/`` (head-camera images), ``metrics/`` (running scores, group counts),
``events`` (scenario events; group events under ``events/truth`` and ``events/<detector>``),
``dataset/`` (characterisation, pair scatter, stress curves).
"""

from __future__ import annotations

from reform._lazy import lazy_exports

# Public name -> the module defining it; loaded on first use, so that declaring a command's
# recording flags (`add_recording_arguments`) does not import Rerun.
_EXPORTS = {
    "default_blueprint": "sim.recording._blueprint",
    "fformations": "sim.recording._colours",
    "group_colour": "sim.recording._colours",
    "match_tracks": "sim.recording._colours",
    "FrameColumns": "sim.recording._columns",
    "DATASET_ROOT": "sim.recording._dataset_views",
    "log_characterisation": "sim.recording._dataset_views",
    "log_pair_scatter": "sim.recording._dataset_views",
    "log_stress_curves": "sim.recording._dataset_views",
    "pair_scatter_data": "sim.recording._dataset_views",
    "KINECT_FIELD_OF_VIEW": "sim.recording._frames",
    "OBSERVED_ROOT": "sim.recording._frames",
    "PEOPLE_ROOT": "sim.recording._frames",
    "ROBOT_ROOT": "sim.recording._frames",
    "WORLD_ROOT": "sim.recording._frames",
    "FieldOfView": "sim.recording._frames",
    "log_frames": "sim.recording._frames",
    "log_world_setup": "sim.recording._frames",
    "GROUPS_ROOT": "sim.recording._groups",
    "TRUTH": "sim.recording._groups",
    "LoggedGroups": "sim.recording._groups",
    "log_groups": "sim.recording._groups",
    "EVENTS_ENTITY": "sim.recording._metrics",
    "METRICS_ROOT": "sim.recording._metrics",
    "Event": "sim.recording._metrics",
    "group_event_text": "sim.recording._metrics",
    "log_events": "sim.recording._metrics",
    "log_group_events": "sim.recording._metrics",
    "stream_group_events": "sim.recording._metrics",
    "log_group_counts": "sim.recording._metrics",
    "log_running_scores": "sim.recording._metrics",
    "pandas_withheld": "sim.recording._arrow",
    "CROWD_PEOPLE": "sim.recording._record",
    "Recorded": "sim.recording._record",
    "record_episode": "sim.recording._record",
    "record_evaluation": "sim.recording._record",
    "record_from_args": "sim.recording._record",
    "CAMERA_ROOT": "sim.recording._scene",
    "MODEL_ROOT": "sim.recording._scene",
    "ROOM_ROOT": "sim.recording._scene",
    "BodyPoses": "sim.recording._scene",
    "CameraImages": "sim.recording._scene",
    "body_entity": "sim.recording._scene",
    "log_body_poses": "sim.recording._scene",
    "log_camera_images": "sim.recording._scene",
    "log_model": "sim.recording._scene",
    "log_room": "sim.recording._scene",
    "person_bodies": "sim.recording._scene",
    "rerun_in_this_shell": "sim.recording._program",
    "rerun_program": "sim.recording._program",
    "stop_viewer": "sim.recording._program",
    "viewer_command": "sim.recording._program",
    "room_bounds": "sim.recording._scene",
    "APPLICATION_ID": "sim.recording._stream",
    "RecordingTarget": "sim.recording._target",
    "add_recording_arguments": "sim.recording._target",
    "open_recording": "sim.recording._stream",
    "recording_id": "sim.recording._stream",
    "target_from_args": "sim.recording._target",
    "FRAME_TIMELINE": "sim.recording._timeline",
    "SIM_TIME_TIMELINE": "sim.recording._timeline",
    "Clock": "sim.recording._timeline",
}

__all__ = sorted(_EXPORTS)


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

"""Rerun recordings, read back from the .rrd files (rerun.chunk.RrdReader, pyarrow)."""

from __future__ import annotations

import argparse
import math
import os
import signal
import subprocess
import sys
import time
from collections import defaultdict
from fractions import Fraction
from pathlib import Path

import mujoco
import numpy as np
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from reform import Frame, FrameBlock, Majority, evaluate, group_events, partition_events
from sim.recording import (
    APPLICATION_ID,
    BodyPoses,
    CameraImages,
    Clock,
    Event,
    FieldOfView,
    FrameColumns,
    RecordingTarget,
    add_recording_arguments,
    body_entity,
    default_blueprint,
    group_event_text,
    log_body_poses,
    log_characterisation,
    log_frames,
    log_groups,
    log_model,
    log_pair_scatter,
    log_stress_curves,
    open_recording,
    pair_scatter_data,
    record_episode,
    record_evaluation,
    recording_id,
    target_from_args,
)

RERUN_CLI = Path(sys.executable).with_name("rerun")
REFORM_SIM = Path(sys.executable).with_name("reform-sim")


@pytest.fixture(autouse=True)
def strict_rerun():
    """Rerun only warns about bad data by default; in tests it must raise."""
    before = rr.strict_mode()
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(before)


# ----------------------------------------------------------------------------- reading back


class Recording:
    """An .rrd file decoded: static components, and per entity the rows of each timeline."""

    def __init__(self, path: Path) -> None:
        reader = RrdReader(path)
        (store,) = reader.recordings()
        self.application_id = store.application_id
        self.recording_id = store.recording_id
        self.static: dict[str, dict[str, object]] = defaultdict(dict)
        rows: dict[str, dict[int, dict[str, object]]] = defaultdict(lambda: defaultdict(dict))
        self.timelines: dict[str, set[str]] = defaultdict(set)
        for chunk in reader.stream():
            batch = chunk.to_record_batch().to_pydict()
            data = {k: v for k, v in batch.items() if not k.startswith("rerun.controls")}
            if chunk.is_static:
                for key, values in data.items():
                    self.static[chunk.entity_path][key] = values[-1]
                continue
            self.timelines[chunk.entity_path].update(chunk.timeline_names)
            for i, frame in enumerate(data["frame"]):
                row = rows[chunk.entity_path][frame]
                for key, values in data.items():
                    row[key] = values[i]
        self.rows = {entity: dict(sorted(by_frame.items())) for entity, by_frame in rows.items()}

    @property
    def entities(self) -> set[str]:
        return set(self.static) | set(self.rows)

    def column(self, entity: str, component: str) -> list:
        """The component's value at every frame, in frame order."""
        return [row.get(component) for row in self.rows[entity].values()]

    def frames(self, entity: str) -> list[int]:
        return list(self.rows[entity])


def content(path: Path) -> list[tuple]:
    """Everything a recording holds, minus row and chunk ids, in a canonical order."""
    out = []
    for chunk in RrdReader(path).stream():
        batch = chunk.to_record_batch()
        keep = [name for name in batch.schema.names if not name.startswith("rerun.controls")]
        out.append((chunk.entity_path, repr(batch.select(keep).to_pydict())))
    return sorted(out)


# ----------------------------------------------------------------------------- synthetic runs

N_PEOPLE = 6
ROBOT_ID = 100


def make_frames(
    n: int, *, seed: int = 0, step_s: float = 0.1, sequence: str = "episode"
) -> list[Frame]:
    """People on a slow random walk with a robot; groups change half way; every 4th frame has
    no ground truth; person 5 leaves for frames 10-14 (people come and go)."""
    rng = np.random.default_rng(seed)
    home = np.array([[0, 0], [1.2, 0], [0.6, 1.0], [4, 4], [5, 4], [8, 0]], dtype=float)
    frames = []
    for t in range(n):
        present = [k for k in range(N_PEOPLE) if not (k == 5 and 10 <= t < 15)]
        position = home[present] + rng.normal(0, 0.05, (len(present), 2)) + 0.01 * t
        yaw = rng.uniform(-math.pi, math.pi, len(present))
        groups = (
            ((0, 1, 2), (3, 4)) if t < n // 2 else ((0, 1), (3, 4, 5) if 5 in present else (3, 4))
        )
        head_yaw = yaw + 0.2
        head_yaw[0] = np.nan  # person 0's head is never seen
        head_position = position.copy()
        head_position[0] = np.nan
        frames.append(
            Frame(
                ids=[*present, ROBOT_ID],
                position=np.vstack([position, [[2.0, -3.0 + 0.01 * t]]]),
                yaw=np.append(yaw, 1.5),
                kinds=["human"] * len(present) + ["robot"],
                head_position=np.vstack([head_position, [[2.0, -3.0 + 0.01 * t]]]),
                head_yaw=np.append((head_yaw + math.pi) % (2 * math.pi) - math.pi, 1.2),
                groups=None if t % 4 == 3 else groups,
                time=round(t * step_s, 6),
                sequence=sequence,
            )
        )
    return frames


def alternating_detector(frames: list[Frame]) -> list[tuple[tuple[int, ...], ...]]:
    """Even frames: perfect truth; odd frames: 0-1 together, 2 joins 3-4, the rest alone."""
    out = []
    for t, frame in enumerate(frames):
        ids = frame.ids.tolist()
        if t % 2 == 0 and frame.groups is not None:
            out.append(frame.partition())
        else:
            groups = [(0, 1), tuple(i for i in (2, 3, 4) if i in ids)]
            grouped = {m for g in groups for m in g}
            out.append(tuple(groups) + tuple((i,) for i in ids if i not in grouped))
    return out


def observe(frames: list[Frame], *, seed: int = 1, truth: bool = True) -> list[Frame]:
    """The robot's view: noisy positions, person 3 dropped every 5th frame; the ground truth
    restricted to who was observed (or none)."""
    rng = np.random.default_rng(seed)
    out = []
    for t, frame in enumerate(frames):
        keep = np.array([not (pid == 3 and t % 5 == 0) for pid in frame.ids.tolist()])
        out.append(
            Frame(
                ids=frame.ids[keep],
                position=frame.position[keep] + rng.normal(0, 0.03, (int(keep.sum()), 2)),
                yaw=frame.yaw[keep],
                kinds=[k for k, m in zip(frame.kinds, keep, strict=True) if m],
                groups=None
                if frame.groups is None or not truth
                else tuple(
                    kept
                    for g in frame.groups
                    if (kept := tuple(m for m in g if m in set(frame.ids[keep].tolist())))
                ),
                time=frame.time,
                sequence=frame.sequence,
            )
        )
    return out


@pytest.fixture(scope="module")
def episode(tmp_path_factory):
    frames = make_frames(24)
    observed = observe(frames)
    detections = {
        "reform": alternating_detector(observed),
        "majority": Majority().fit(observed).predict(observed),
    }
    path = tmp_path_factory.mktemp("episode") / "run.rrd"
    events = [Event(0.5, "turn starts"), (1.25, "shuffle", "WARN")]
    recorded = record_episode(
        path, frames, observed=observed, detections=detections, events=events, seed=7
    )
    return {
        "path": path,
        "frames": frames,
        "observed": observed,
        "detections": detections,
        "recorded": recorded,
        "rec": Recording(path),
    }


# ----------------------------------------------------------------------------- the episode


def test_episode_identity_entities_and_rows_per_timeline(episode):
    rec = episode["rec"]
    n = len(episode["frames"])
    assert rec.application_id == APPLICATION_ID == "reform-sim"
    assert rec.recording_id == recording_id("episode", seed=7) == episode["recorded"].recording_id
    per_frame = {
        "/world/people/bodies",
        "/world/people/labels",
        "/world/people/body_facing",
        "/world/people/head_facing",
        "/world/people/trails",
        "/world/robot/bodies",
        "/world/robot/labels",
        "/world/robot/body_facing",
        "/world/robot/head_facing",
        "/world/robot/trails",
        "/world/robot/field_of_view",
        "/world/observed/people",
        "/world/observed/body_facing",
        *(
            f"/world/groups/{tree}/{part}"
            for tree in ("truth", "reform", "majority")
            for part in ("members", "centres", "circles")
        ),
        *(
            f"/world/groups/{d}/mistakes/{kind}"
            for d in ("reform", "majority")
            for kind in ("missed", "spurious", "wrong_members")
        ),
    }
    assert per_frame <= rec.entities
    assert {"/world", "/world/room/floor", "/world/room/outline", "/world/groups/truth"} <= set(
        rec.static
    )
    clock = Clock.from_frames(episode["frames"])
    for entity in per_frame:
        assert rec.timelines[entity] == {"frame", "sim_time"}, entity
        assert rec.frames(entity) == list(range(n)), entity
        sim_time = [t.total_seconds() for t in rec.column(entity, "sim_time")]
        np.testing.assert_allclose(sim_time, clock.sim_time, atol=1e-9)
    annotated = [t for t, f in enumerate(episode["frames"]) if f.groups is not None]
    for score in ("precision", "recall", "f1"):
        assert rec.frames(f"/metrics/{score}/reform") == annotated
    assert rec.frames("/metrics/groups/truth") == annotated
    assert rec.frames("/metrics/groups/reform") == list(range(n))
    assert "log_time" not in set().union(*rec.timelines.values())
    assert "log_tick" not in set().union(*rec.timelines.values())


def test_people_and_robot_positions_and_facings_equal_the_frames(episode):
    rec = episode["rec"]
    for t, frame in enumerate(episode["frames"]):
        human = ~frame.is_robot
        labels = np.array(rec.rows["/world/people/labels"][t]["Points3D:positions"])
        np.testing.assert_allclose(labels[:, :2], frame.position[human], atol=1e-5)
        assert rec.rows["/world/people/labels"][t]["person_id"] == frame.ids[human].tolist()
        capsules = np.array(rec.rows["/world/people/bodies"][t]["Capsules3D:translations"])
        np.testing.assert_allclose(capsules[:, :2], frame.position[human], atol=1e-5)
        vectors = np.array(rec.rows["/world/people/body_facing"][t]["Arrows3D:vectors"])
        np.testing.assert_allclose(
            np.arctan2(vectors[:, 1], vectors[:, 0]), frame.yaw[human], atol=1e-5
        )
        seen = np.isfinite(frame.head_yaw) & human
        heads = np.array(rec.rows["/world/people/head_facing"][t]["Arrows3D:origins"])
        np.testing.assert_allclose(heads[:, :2], frame.head_position[seen], atol=1e-5)
        robot = np.array(rec.rows["/world/robot/labels"][t]["Points3D:positions"])
        np.testing.assert_allclose(robot[:, :2], frame.position[frame.is_robot], atol=1e-5)
        trails = rec.rows["/world/people/trails"][t]["LineStrips3D:strips"]
        assert len(trails) == int(human.sum())
        for strip, pid in zip(trails, frame.ids[human].tolist(), strict=True):
            np.testing.assert_allclose(
                strip[-1][:2], frame.position[frame.index_of(pid)], atol=1e-5
            )


def test_trails_cover_the_last_seconds_of_each_path(episode):
    rec = episode["rec"]
    frames = episode["frames"]
    t = 20  # 2 s trails at 10 Hz: frames 0.0-2.0 s back, at most 8 points, oldest first
    strips = rec.rows["/world/people/trails"][t]["LineStrips3D:strips"]
    first = np.array(strips[0])
    assert 2 <= len(first) <= 8
    oldest_time = min(f.time for f in frames if f.time >= frames[t].time - 2.0 - 1e-9)
    oldest = next(f for f in frames if f.time == oldest_time)
    np.testing.assert_allclose(first[0][:2], oldest.position[oldest.index_of(0)], atol=1e-5)
    # Person 5 was away for frames 10-14: its trail at frame 16 starts at frame 15.
    row = frames[16].ids.tolist().index(5)
    strip = np.array(rec.rows["/world/people/trails"][16]["LineStrips3D:strips"][row])
    back = np.array([f.position[f.index_of(5)] for f in frames[15:17]])
    np.testing.assert_allclose(strip[:, :2], back, atol=1e-5)


def test_observed_people_with_dropouts(episode):
    rec = episode["rec"]
    for t, frame in enumerate(episode["observed"]):
        human = ~frame.is_robot
        row = rec.rows["/world/observed/people"][t]
        assert row["person_id"] == frame.ids[human].tolist()
        np.testing.assert_allclose(
            np.array(row["Points3D:positions"])[:, :2], frame.position[human], atol=1e-5
        )
    assert 3 not in rec.rows["/world/observed/people"][0]["person_id"]
    fov = rec.rows["/world/robot/field_of_view"][0]["LineStrips3D:strips"]
    (wedge,) = fov
    apex = episode["frames"][0].head_position[-1]
    far = np.linalg.norm(np.array(wedge)[:, :2] - apex, axis=1)
    assert far.max() == pytest.approx(FieldOfView().max_range_m, rel=1e-5)
    assert far.min() == pytest.approx(FieldOfView().min_range_m, rel=1e-5)


def partitions_from(rec: Recording, entity: str) -> dict[int, set[frozenset[int]]]:
    out = {}
    for frame, row in rec.rows[entity].items():
        groups: dict[int, set[int]] = defaultdict(set)
        for pid, g in zip(row.get("person_id") or [], row.get("group_index") or [], strict=True):
            groups[g].add(pid)
        out[frame] = {frozenset(g) for g in groups.values()}
    return out


def test_logged_groups_equal_truth_and_detections(episode):
    rec = episode["rec"]
    truth = partitions_from(rec, "/world/groups/truth/members")
    for t, frame in enumerate(episode["frames"]):
        if frame.groups is None:
            assert truth[t] == set()
        else:
            assert truth[t] == {frozenset(g) for g in frame.partition()}
    for name, partitions in episode["detections"].items():
        logged = partitions_from(rec, f"/world/groups/{name}/members")
        for t, partition in enumerate(partitions):
            assert logged[t] == {frozenset(g) for g in partition}, (name, t)
        for t, frame in enumerate(episode["observed"]):
            row = rec.rows[f"/world/groups/{name}/members"][t]
            rows = [frame.index_of(pid) for pid in row["person_id"]]
            np.testing.assert_allclose(
                np.array(row["Cylinders3D:centers"])[:, :2], frame.position[rows], atol=1e-5
            )


def test_group_colours_follow_groups_and_matches(episode):
    rec = episode["rec"]
    for tree in ("truth", "reform"):
        for row in rec.rows[f"/world/groups/{tree}/members"].values():
            by_group: dict[int, set[int]] = defaultdict(set)
            sizes: dict[int, int] = defaultdict(int)
            for g, c in zip(
                row.get("group_index") or [], row.get("Cylinders3D:class_ids") or [], strict=True
            ):
                by_group[g].add(c)
                sizes[g] += 1
            for g, classes in by_group.items():
                assert len(classes) == 1
                assert (classes == {0}) == (sizes[g] == 1)
    # A true group keeps its colour while it keeps its members.
    t0, t1 = 0, 1
    truth_rows = rec.rows["/world/groups/truth/members"]
    assert truth_rows[t0]["Cylinders3D:class_ids"] == truth_rows[t1]["Cylinders3D:class_ids"]
    # Even frames of "reform" are perfect: each of its groups has its true group's colour.
    reform_rows = rec.rows["/world/groups/reform/members"]
    for t in (2, 4, 6):  # (person 3 is not observed at frame 0)
        truth_colour = dict(
            zip(truth_rows[t]["person_id"], truth_rows[t]["Cylinders3D:class_ids"], strict=True)
        )
        reform_colour = dict(
            zip(reform_rows[t]["person_id"], reform_rows[t]["Cylinders3D:class_ids"], strict=True)
        )
        assert {p: c for p, c in reform_colour.items() if p in truth_colour} == truth_colour
    labels = {info["label"] for info in _context(rec, "/world/groups/truth")}
    assert {"alone", "group 1", "group 2"} <= labels


def _context(rec: Recording, entity: str) -> list[dict]:
    """The class descriptions of an annotation context."""
    (context,) = rec.static[entity]["AnnotationContext:context"]
    return [entry["class_description"]["info"] for entry in context]


def test_mistakes_name_missed_spurious_and_wrong_members(tmp_path):
    frame = Frame(
        ids=[1, 2, 3, 4, 5, 6, 7, 8],
        position=[[0, 0], [1, 0], [0.5, 1], [5, 5], [6, 5], [0.5, -1], [9, 0], [10, 0]],
        yaw=np.zeros(8),
        groups=((1, 2, 3), (4, 5)),
        sequence="s",
    )
    # (1,2,3,6) matches (1,2,3) at T = 2/3 (3*3 >= 2*4) with 6 extra; (4,5) is missed; (7,8) is
    # spurious.
    prediction = ((1, 2, 3, 6), (4,), (5,), (7, 8))
    path = tmp_path / "mistakes.rrd"
    record_evaluation(path, [frame], {"reform": [prediction]}, dataset_views=False)
    rec = Recording(path)
    missed = rec.rows["/world/groups/reform/mistakes/missed"][0]
    spurious = rec.rows["/world/groups/reform/mistakes/spurious"][0]
    wrong = rec.rows["/world/groups/reform/mistakes/wrong_members"][0]
    assert missed["Cylinders3D:labels"] == ["missed 4,5"]
    assert spurious["Cylinders3D:labels"] == ["spurious 7,8"]
    assert wrong["Points3D:labels"] == ["extra 6"]
    np.testing.assert_allclose(np.array(wrong["Points3D:positions"])[0, :2], [0.5, -1])
    # the missed ring: centre (5.5, 5), Tightness 0.5 m plus the 0.25 m mistake margin
    np.testing.assert_allclose(np.array(missed["Cylinders3D:centers"])[:, :2], [[5.5, 5.0]])
    np.testing.assert_allclose(missed["Cylinders3D:radii"], [0.75])
    centres = rec.rows["/world/groups/reform/centres"][0]["Points3D:positions"]
    np.testing.assert_allclose(np.array(centres)[:, :2], [[0.5, 0.0], [9.5, 0.0]], atol=1e-6)
    circles = rec.rows["/world/groups/reform/circles"][0]
    np.testing.assert_allclose(
        np.array(circles["Cylinders3D:centers"])[:, :2], centres_xy := np.array(centres)[:, :2]
    )
    tightness_123_6 = np.linalg.norm(frame.position[[0, 1, 2, 5]] - centres_xy[0], axis=1).mean()
    np.testing.assert_allclose(circles["Cylinders3D:radii"], [tightness_123_6, 0.5], rtol=1e-6)


def test_running_scores_end_at_the_evaluation(episode):
    rec = episode["rec"]
    for name in ("reform", "majority"):
        evaluation = episode["recorded"].evaluations[name]
        scores = evaluation.at(Fraction(2, 3))
        final = {
            s: rec.column(f"/metrics/{s}/{name}", "Scalars:scalars")[-1][0]
            for s in ("precision", "recall", "f1")
        }
        assert final["precision"] == pytest.approx(scores.precision)
        assert final["recall"] == pytest.approx(scores.recall)
        assert final["f1"] == pytest.approx(scores.f1)
        first = rec.column(f"/metrics/precision/{name}", "Scalars:scalars")[0][0]
        assert first == pytest.approx(scores.frame_precision[0])
    # the majority baseline detects nothing: precision 1 and recall 0 at every annotated frame
    assert set(np.ravel(rec.column("/metrics/recall/majority", "Scalars:scalars"))) == {0.0}
    counts = np.ravel(rec.column("/metrics/groups/truth", "Scalars:scalars"))
    annotated = [f for f in episode["frames"] if f.groups is not None]
    assert counts.tolist() == [len(f.fformations()) for f in annotated]


def test_observed_frames_without_truth_are_scored_on_the_world_truth_of_who_was_seen(tmp_path):
    frames = make_frames(12)
    blind = observe(frames, truth=False)
    detections = {"reform": alternating_detector(observe(frames))}
    recorded = record_episode(tmp_path / "blind.rrd", frames, observed=blind, detections=detections)
    expected = evaluate(observe(frames), detections["reform"]).at("2/3")
    assert recorded.evaluations["reform"].at("2/3").f1 == pytest.approx(expected.f1)
    assert recorded.evaluations["reform"].n_frames == sum(f.groups is not None for f in frames)


def text_log(path: Path, entity: str) -> list[tuple[int, str, str]]:
    """(frame, text, level) of every line of a text log, in the order logged."""
    entries = []  # several lines may share a frame: read the chunks, not the merged rows
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == entity:
            data = chunk.to_record_batch().to_pydict()
            texts, levels = data["TextLog:text"], data["TextLog:level"]
            entries += [
                (f, text[0], level[0])
                for f, text, level in zip(data["frame"], texts, levels, strict=True)
            ]
    return entries


def test_events_hold_the_scenario_events_and_group_events_beside_them(episode):
    path = episode["path"]
    assert text_log(path, "/events") == [(5, "turn starts", "INFO"), (12, "shuffle", "WARN")]
    # Hand-computed from make_frames(24): groups {0,1,2} (track 1) and {3,4} (track 2); at
    # frame 12 (annotated, person 5 away) 2 has left {0,1,2}; at frame 16 (the first annotated
    # frame with 5 back, 15 being unannotated) 5 has joined {3,4}.
    assert text_log(path, "/events/truth") == [
        (12, "2 leaves group 1: {0, 1, 2}", "INFO"),
        (16, "5 joins group 2: {3, 4, 5}", "INFO"),
    ]
    # The detector's events, found by the same rules on the frames the stream annotates.
    observed, partitions = episode["observed"], episode["detections"]["reform"]
    expected = partition_events(
        [p if f.groups is not None else None for f, p in zip(observed, partitions, strict=True)],
        times=[f.time for f in observed],
        sequences="episode",
    )
    assert expected  # the alternating detector flickers
    assert text_log(path, "/events/reform") == [
        (e.frame, group_event_text(e), "INFO") for e in expected
    ]
    # The majority baseline (everyone alone) has no group, hence no event and no log.
    assert "/events/majority" not in episode["rec"].entities


def test_group_event_lines_name_the_kind_the_group_and_the_people():
    # reform.events' worked example (docs/guide/temporal.md): one event of every kind.
    partitions = [
        ((1, 2, 3),),
        ((1, 2, 3, 4),),
        ((1, 2, 3, 4), (5, 6)),
        ((1, 2, 3, 4, 5, 6),),
        ((1, 2, 3), (4, 5, 6)),
        ((1, 2), (4, 5, 6)),
        ((4, 5, 6),),
    ]
    events = partition_events(partitions, times=range(7), sequences="s")
    assert [group_event_text(e) for e in events] == [
        "4 joins group 1: {1, 2, 3, 4}",
        "group 2 forms: {5, 6}",
        "groups 1 {1, 2, 3, 4} and 2 {5, 6} merge into group 1: {1, 2, 3, 4, 5, 6}",
        "group 1 {1, 2, 3, 4, 5, 6} splits into groups 1 {1, 2, 3} and 3 {4, 5, 6}",
        "3 leaves group 1: {1, 2, 3}",
        "group 1 dissolves: {1, 2}",
    ]


def test_two_runs_with_one_seed_have_equal_content(tmp_path, episode):
    frames, observed, detections = episode["frames"], episode["observed"], episode["detections"]
    again = tmp_path / "again.rrd"
    record_episode(
        again,
        frames,
        observed=observed,
        detections=detections,
        events=[Event(0.5, "turn starts"), (1.25, "shuffle", "WARN")],
        seed=7,
    )
    assert content(again) == content(episode["path"])
    env = {**os.environ, "CI": "1"}  # keeps the CLI's usage analytics off
    same = subprocess.run(
        [RERUN_CLI, "rrd", "compare", "--unordered", again, episode["path"]],
        capture_output=True,
        env=env,
    )
    assert same.returncode == 0, same.stderr.decode()[-2000:]
    other = tmp_path / "other.rrd"
    record_episode(other, make_frames(24, seed=1), seed=7)
    differ = subprocess.run(
        [RERUN_CLI, "rrd", "compare", "--unordered", other, episode["path"]],
        capture_output=True,
        env=env,
    )
    assert differ.returncode != 0
    assert RrdReader(other).recordings()[0].recording_id == recording_id("episode", seed=7)
    assert recording_id("episode", seed=8) != recording_id("episode", seed=7)


def test_sequences_follow_each_other_on_sim_time(tmp_path):
    frames = make_frames(6, sequence="a") + make_frames(4, sequence="b", step_s=0.5)
    clock = Clock.from_frames(frames)
    np.testing.assert_allclose(clock.sim_time, [0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1.1, 1.6, 2.1])
    assert clock.row_at(0.7, sequence="b") == 7
    assert clock.sim_time_at(0.7, sequence="b") == pytest.approx(1.3)
    path = tmp_path / "two.rrd"
    record_evaluation(path, frames, {"reform": alternating_detector(frames)}, dataset_views=False)
    rec = Recording(path)
    sim_time = [t.total_seconds() for t in rec.column("/world/people/labels", "sim_time")]
    np.testing.assert_allclose(sim_time, clock.sim_time, atol=1e-9)
    # trails do not reach back into the previous sequence
    strips = rec.rows["/world/people/trails"][6]["LineStrips3D:strips"]
    assert all(len(strip) == 1 for strip in strips)


# ----------------------------------------------------------------------------- columns, edge cases


def random_run(seed: int, n: int = 120) -> list[Frame]:
    """Two sequences of people coming and going, the robot now there, now not, heads seen or
    not (or not tracked at all), people listed in any order, an empty frame, frames without
    ground truth and an annotated frame where nobody is grouped."""
    rng = np.random.default_rng(seed)
    frames = []
    for sequence, step_s in (("a", 0.125), ("b", 0.5)):  # (exact in binary: sim_time too)
        present = set(range(7))
        home = rng.uniform(0.0, 6.0, (9, 2))
        groups: tuple[tuple[int, ...], ...] = ()
        for t in range(n // 2):
            if rng.random() < 0.2:
                present ^= {int(rng.integers(0, 9))}
            ids = [] if t == 5 else sorted(present)
            if rng.random() < 0.3:
                rng.shuffle(ids)
            if t == 0 or rng.random() < 0.25 or not {m for g in groups for m in g} <= set(ids):
                order = rng.permutation(ids).tolist()
                cuts = np.sort(rng.choice(np.arange(1, max(len(order), 2)), 2)).tolist()
                parts = [order[: cuts[0]], order[cuts[0] : cuts[1]], order[cuts[1] :]]
                groups = tuple(tuple(p) for p in parts if p and rng.random() < 0.85)
            robot = rng.random() < 0.7 and t != 5
            n_people = len(ids) + robot
            position = np.array([home[i] for i in ids] + [[3.0, -2.0]] * robot).reshape(-1, 2)
            position = position + rng.normal(0.0, 0.05, position.shape)
            head_position = position + 0.05
            head_position[rng.random(n_people) < 0.3] = np.nan
            head_yaw = np.where(np.isnan(head_position[:, 0]), np.nan, 0.5)
            tracked = rng.random() < 0.8
            frames.append(
                Frame(
                    ids=[*ids, *([ROBOT_ID] * robot)],
                    position=position,
                    yaw=rng.uniform(-3.0, 3.0, n_people),
                    kinds=["human"] * len(ids) + ["robot"] * robot,
                    head_position=head_position if tracked else None,
                    head_yaw=head_yaw if tracked else None,
                    groups=None if t % 4 == 3 else () if t == 8 else groups,
                    time=round(t * step_s, 6),
                    sequence=sequence,
                )
            )
    return frames


def random_detector(frames: list[Frame], seed: int) -> list[tuple[tuple[int, ...], ...]]:
    """Partitions that often repeat, often follow the truth with a merge, a split or a person
    moved, and sometimes are anything."""
    rng = np.random.default_rng(seed)
    out: list[tuple[tuple[int, ...], ...]] = []
    for k, frame in enumerate(frames):
        ids = frame.ids.tolist()
        if k and ids == frames[k - 1].ids.tolist() and rng.random() < 0.4:
            out.append(out[-1])
            continue
        if frame.groups is not None and rng.random() < 0.7:
            part = [list(g) for g in frame.partition()]
            move = rng.random()
            if move < 0.3 and len(part) > 1:
                part[0] += part.pop(1)
            elif move < 0.6 and part and len(part[0]) > 2:
                part[0:1] = [part[0][:1], part[0][1:]]
            elif move < 0.8 and len(part) > 1 and len(part[0]) > 1:
                part[1].append(part[0].pop())
        else:
            order = rng.permutation(ids).tolist()
            half = int(rng.integers(0, len(order) + 1))
            part = [order[:half], order[half:]]
        out.append(tuple(tuple(g) for g in part if g))
    return out


def reference_matching(trues, groups) -> dict[frozenset[int], frozenset[int]]:
    """Detected group -> the true group it stands for, plainly: of every one-to-one matching of
    overlapping groups, the one of largest summed Jaccard index (then the smallest summed pair
    index ``i * len(trues) + j``), found by trying them all."""
    best, best_key = {}, None

    def walk(i, used, pairs, total, index):
        nonlocal best, best_key
        if i == len(groups):
            key = (round(total, 9), -index)
            if best_key is None or key > best_key:
                best, best_key = dict(pairs), key
            return
        walk(i + 1, used, pairs, total, index)
        for j, true in enumerate(trues):
            shared = len(groups[i] & true)
            if j in used or not shared:
                continue
            pairs[groups[i]] = true
            walk(
                i + 1,
                used | {j},
                pairs,
                total + shared / len(groups[i] | true),
                index + i * len(trues) + j,
            )
            del pairs[groups[i]]

    walk(0, frozenset(), {}, 0.0, 0)
    return best


def reference_tracks(
    frames, partitions, *, truth=None, first_track=1
) -> list[dict[frozenset[int], int]]:
    """Each frame's F-formation -> colour, the rule written plainly: a group keeps its track
    while it keeps a majority of its members; given the truth's tracks, a detected group
    matched to a true group of its frame (`reference_matching`) takes its track."""
    out, previous, sequence, next_track = [], [], None, first_track
    for t, (frame, partition) in enumerate(zip(frames, partitions, strict=True)):
        if frame.sequence != sequence:
            previous, sequence = [], frame.sequence
        if partition is None or not frame.n_people:
            out.append({})
            continue
        groups = [frozenset(g) for g in partition if len(g) >= 2]
        fixed = {}
        if truth is not None and frame.groups is not None:
            trues = [frozenset(g) for g in frame.groups if len(g) >= 2]
            for group, true in reference_matching(trues, groups).items():
                fixed[group] = truth[t][true]
        current, used = [], set(fixed.values())
        for group in groups:
            track = fixed.get(group) or next(
                (
                    k
                    for old, k in previous
                    if k not in used and 2 * len(group & old) > max(len(group), len(old))
                ),
                None,
            )
            if track is None:
                track, next_track = next_track, next_track + 1
            used.add(track)
            current.append((group, track))
        previous = current
        out.append(dict(current))
    return out


def reference_mistakes(frame: Frame, partition) -> tuple[list[str], list[str], list[str]]:
    """Missed, spurious and wrong-member labels of one annotated frame (T = 2/3), plainly."""
    trues = [tuple(g) for g in frame.groups if len(g) >= 2]
    found = [tuple(g) for g in partition if len(g) >= 2]

    def fits(a, b):
        return 3 * len(set(a) & set(b)) >= 2 * max(len(a), len(b))

    missed, wrong = [], []
    for true in trues:
        matched = any(fits(d, true) for d in found)
        if matched and any(set(d) == set(true) for d in found):
            continue
        if not matched:
            missed.append("missed " + ",".join(map(str, true)))
            continue
        partner = max(found, key=lambda d: len(set(d) & set(true)))
        wrong += [f"extra {p}" for p in sorted(set(partner) - set(true))]
        wrong += [f"missing {p}" for p in sorted(set(true) - set(partner))]
    spurious = [
        "spurious " + ",".join(map(str, d)) for d in found if not any(fits(d, t) for t in trues)
    ]
    return missed, spurious, wrong


@pytest.fixture(scope="module")
def random_episode(tmp_path_factory):
    frames = random_run(5)
    detections = {f"d{k}": random_detector(frames, k) for k in (1, 2, 3)}
    path = tmp_path_factory.mktemp("random") / "random.rrd"
    record_episode(path, frames, detections=detections, events=[Event(0.2, "start")], seed=3)
    return {"frames": frames, "detections": detections, "path": path, "rec": Recording(path)}


def test_random_runs_log_every_entity_once_per_frame_on_both_timelines(random_episode):
    rec, frames = random_episode["rec"], random_episode["frames"]
    clock = Clock.from_frames(frames)
    per_frame = [
        e
        for e in rec.rows
        if e.startswith(("/world/people", "/world/robot", "/world/groups"))
        and not e.endswith("/field_of_view")
    ]
    assert len(per_frame) == 5 + 5 + 4 * 3 + 3 * 3
    for entity in per_frame:
        assert rec.frames(entity) == list(range(len(frames))), entity
        assert rec.timelines[entity] == {"frame", "sim_time"}, entity
        sim_time = [t.total_seconds() for t in rec.column(entity, "sim_time")]
        np.testing.assert_allclose(sim_time, clock.sim_time, atol=1e-6)
    robot_frames = [t for t, f in enumerate(frames) if f.is_robot.any()]
    strips = rec.column("/world/robot/field_of_view", "LineStrips3D:strips")
    assert [t for t, s in enumerate(strips) if s] == robot_frames


def test_random_runs_log_exactly_the_frames_people(random_episode):
    rec, frames = random_episode["rec"], random_episode["frames"]
    for t, frame in enumerate(frames):
        for root, mask in (("people", ~frame.is_robot), ("robot", frame.is_robot)):
            row = rec.rows[f"/world/{root}/labels"][t]
            assert (row.get("person_id") or []) == frame.ids[mask].tolist()
            positions = np.array(row.get("Points3D:positions") or np.zeros((0, 3)))
            np.testing.assert_allclose(positions[:, :2], frame.position[mask], atol=1e-5)
            heads = rec.rows[f"/world/{root}/head_facing"][t].get("Arrows3D:origins") or []
            seen = np.zeros(frame.n_people, bool)
            if frame.head_yaw is not None:
                seen = np.isfinite(frame.head_yaw)
            assert len(heads) == int((seen & mask).sum())
            strips = rec.rows[f"/world/{root}/trails"][t].get("LineStrips3D:strips") or []
            assert len(strips) == int(mask.sum())
            for strip, k in zip(strips, np.flatnonzero(mask).tolist(), strict=True):
                np.testing.assert_allclose(strip[-1][:2], frame.position[k], atol=1e-5)


def test_random_runs_log_exactly_the_groups_and_their_shapes(random_episode):
    rec, frames = random_episode["rec"], random_episode["frames"]
    trees = {
        "truth": [f.partition() if f.groups is not None else None for f in frames],
        **random_episode["detections"],
    }
    for name, partitions in trees.items():
        for t, (frame, partition) in enumerate(zip(frames, partitions, strict=True)):
            members = rec.rows[f"/world/groups/{name}/members"][t]
            expected = [] if partition is None else list(partition)
            flat = [(m, g) for g, group in enumerate(expected) for m in group]
            assert (members.get("person_id") or []) == [m for m, _ in flat], (name, t)
            assert (members.get("group_index") or []) == [g for _, g in flat], (name, t)
            xy = np.array(members.get("Cylinders3D:centers") or np.zeros((0, 3)))[:, :2]
            np.testing.assert_allclose(
                xy, frame.position[[frame.index_of(m) for m, _ in flat]].reshape(-1, 2), atol=1e-5
            )
            fformations = [g for g in expected if len(g) >= 2]
            centres = rec.rows[f"/world/groups/{name}/centres"][t].get("Points3D:positions")
            circles = rec.rows[f"/world/groups/{name}/circles"][t].get("Cylinders3D:radii")
            assert len(centres or []) == len(circles or []) == len(fformations), (name, t)
            for group, centre, radius in zip(
                fformations, centres or [], circles or [], strict=True
            ):
                where = frame.position[[frame.index_of(m) for m in group]]
                mean = where.mean(axis=0)
                np.testing.assert_allclose(centre[:2], mean, atol=1e-5)
                tightness = np.linalg.norm(where - mean, axis=1).mean()
                assert radius == pytest.approx(max(tightness, 0.15), abs=1e-5)


def test_random_runs_colour_groups_by_the_majority_rule(random_episode):
    rec, frames = random_episode["rec"], random_episode["frames"]
    truth_tracks = reference_tracks(
        frames, [f.partition() if f.groups is not None else None for f in frames]
    )
    trees = {"truth": truth_tracks}
    for name, partitions in random_episode["detections"].items():
        # Each detector's unmatched groups take tracks after every earlier tree's.
        first = 1 + max(k for tree in trees.values() for tracks in tree for k in tracks.values())
        trees[name] = reference_tracks(frames, partitions, truth=truth_tracks, first_track=first)
    for name, by_frame in trees.items():
        for t, tracks in enumerate(by_frame):
            row = rec.rows[f"/world/groups/{name}/members"][t]
            expected = [
                next((k for g, k in tracks.items() if m in g), 0)
                for m in row.get("person_id") or []
            ]
            assert (row.get("Cylinders3D:class_ids") or []) == expected, (name, t)


def test_random_runs_name_exactly_the_mistakes(random_episode):
    rec, frames = random_episode["rec"], random_episode["frames"]
    for name, partitions in random_episode["detections"].items():
        root = f"/world/groups/{name}/mistakes"
        for t, (frame, partition) in enumerate(zip(frames, partitions, strict=True)):
            missed, spurious, wrong = (
                ([], [], []) if frame.groups is None else reference_mistakes(frame, partition)
            )
            assert (rec.rows[f"{root}/missed"][t].get("Cylinders3D:labels") or []) == missed
            assert (rec.rows[f"{root}/spurious"][t].get("Cylinders3D:labels") or []) == spurious
            row = rec.rows[f"{root}/wrong_members"][t]
            assert (row.get("Points3D:labels") or []) == wrong, (name, t)
            people = [int(label.split()[1]) for label in wrong]
            xy = np.array(row.get("Points3D:positions") or np.zeros((0, 3)))[:, :2]
            where = frame.position[[frame.index_of(p) for p in people]].reshape(-1, 2)
            np.testing.assert_allclose(xy, where, atol=1e-5)


def test_random_runs_log_the_group_events_of_the_truth_and_of_each_detector(random_episode):
    frames, path = random_episode["frames"], random_episode["path"]
    assert text_log(path, "/events") == [(1, "start", "INFO")]  # 0.2 s: frame 1 (0.125 s)
    # Two sequences, one after the other on the timeline: reform.group_events on the Frames.
    truth = group_events(frames)
    assert {e.sequence for e in truth} == {"a", "b"}
    assert text_log(path, "/events/truth") == [
        (e.frame, group_event_text(e), "INFO") for e in truth
    ]
    for name, partitions in random_episode["detections"].items():
        annotated = [
            p if f.groups is not None else None for f, p in zip(frames, partitions, strict=True)
        ]
        found = partition_events(
            annotated, times=[f.time for f in frames], sequences=[f.sequence for f in frames]
        )
        logged = text_log(path, f"/events/{name}")
        assert logged == [(e.frame, group_event_text(e), "INFO") for e in found], name
        assert len(logged) > len(truth)  # random groups change more often than the truth


def test_columns_hold_what_the_frames_hold():
    frames = random_run(2)
    columns = FrameColumns.of(frames)
    assert len(columns) == len(frames) and columns.frames == tuple(frames)
    assert columns.counts.tolist() == [f.n_people for f in frames]
    for t, frame in enumerate(frames):
        rows = slice(columns.starts[t], columns.starts[t + 1])
        assert columns.ids[rows].tolist() == frame.ids.tolist()
        assert columns.robot[rows].tolist() == frame.is_robot.tolist()
        np.testing.assert_array_equal(columns.position[rows], frame.position)
        np.testing.assert_array_equal(columns.yaw[rows], frame.yaw)
        heads = frame.head_yaw if frame.head_yaw is not None else np.full(frame.n_people, np.nan)
        np.testing.assert_array_equal(columns.head_yaw[rows], heads)
        assert columns.time[t] == frame.time and columns.sequence[t] == frame.sequence
        assert columns.groups[t] == frame.groups
    assert columns.counts[5] == 0  # the empty frame
    assert columns.same_people_as_previous()[1:].tolist() == [
        a.ids.tolist() == b.ids.tolist() for a, b in zip(frames, frames[1:], strict=False)
    ]
    with pytest.raises(ValueError, match=r"frames\[1\] must be a reform\.Frame, got str"):
        FrameColumns.of([frames[0], "frame"])
    with pytest.raises(ValueError, match=r"FrameColumns\.yaw must have shape \(3,\), got \(2,\)"):
        FrameColumns(
            counts=np.array([3]),
            frame=np.zeros(3, int),
            ids=np.arange(3),
            robot=np.zeros(3, bool),
            position=np.zeros((3, 2)),
            yaw=np.zeros(2),
            head_position=np.zeros((3, 2)),
            head_yaw=np.zeros(3),
            time=np.zeros(1),
            sequence=("s",),
            groups=(None,),
        )


def test_pose_blocks_make_the_columns_of_their_frames(tmp_path):
    from sim.episode import episode_blocks

    blocks = list(episode_blocks("word-improv", seed=3, duration=20, rate=2, block_rows=16))
    rng = np.random.default_rng(0)
    present = np.ones((6, 3), bool)
    present[2:4, 1] = False  # person 2 leaves for two frames
    present[5, :] = False  # nobody
    made = FrameBlock(
        time=np.arange(6) * 0.5 + 30.0,
        ids=np.array([1, 2, 100]),
        kinds=("human", "human", "robot"),
        present=present,
        position=rng.normal(size=(6, 3, 2)),
        yaw=rng.uniform(-3, 3, (6, 3)),
        head_position=rng.normal(size=(6, 3, 2)),
        head_yaw=rng.uniform(-3, 3, (6, 3)),
        groups=(((1, 2),), ((1, 2),), ((1, 2),), None, ((1, 2),), ((1, 2),)),
        sequence=blocks[0].sequence,
    )
    blocks.append(made)
    columns = FrameColumns.from_blocks(blocks)
    frames = [frame for block in blocks for frame in block.frames()]
    expected = FrameColumns.of(frames)
    for name in ("counts", "frame", "ids", "robot", "position", "yaw", "head_position", "time"):
        np.testing.assert_array_equal(getattr(columns, name), getattr(expected, name), name)
    assert columns.sequence == expected.sequence and columns.groups == expected.groups
    assert columns.groups[-4:] == (((1,),), None, ((1, 2),), ())
    record_episode(tmp_path / "blocks.rrd", columns, seed=1, name="run")
    record_episode(tmp_path / "frames.rrd", frames, seed=1, name="run")
    assert content(tmp_path / "blocks.rrd") == content(tmp_path / "frames.rrd")
    with pytest.raises(ValueError, match="scoring d needs the frames it ran on: pass evaluation="):
        record_episode(tmp_path / "x.rrd", columns, detections={"d": Majority().predict(frames)})


def test_a_simulated_episode_is_logged_as_simulated_and_detected(tmp_path):
    from sim.episode import simulate_episode

    episode = simulate_episode(
        "word-improv", seed=4, duration=30, rate=2, view="robot", options={"robot": "watch"}
    )
    observed = episode.dataset.frames
    detections = {"majority": Majority().predict(observed), "det": random_detector(observed, 3)}
    path = tmp_path / "sim.rrd"
    record_episode(path, episode.truth, observed=observed, detections=detections)
    rec = Recording(path)
    n = len(episode.truth)
    for entity in ("/world/people/labels", "/world/robot/field_of_view", "/world/observed/people"):
        assert rec.frames(entity) == list(range(n))
    for t, (world, seen) in enumerate(zip(episode.truth, observed, strict=True)):
        human = ~world.is_robot
        row = rec.rows["/world/people/labels"][t]
        assert row["person_id"] == world.ids[human].tolist()
        np.testing.assert_allclose(
            np.array(row["Points3D:positions"])[:, :2], world.position[human], atol=1e-5
        )
        row = rec.rows["/world/observed/people"][t]
        assert (row.get("person_id") or []) == seen.ids[~seen.is_robot].tolist()
        assert partitions_from(rec, "/world/groups/truth/members")[t] == {
            frozenset(g) for g in world.partition()
        }
        for name, partitions in detections.items():
            logged = partitions_from(rec, f"/world/groups/{name}/members")[t]
            assert logged == {frozenset(g) for g in partitions[t]}


def test_partitions_as_lists_or_arrays_log_as_tuples_do(tmp_path):
    frames = random_run(7, n=24)
    tuples = random_detector(frames, 4)
    forms = {
        "tuples": tuples,
        "lists": [[list(g) for g in p] for p in tuples],
        "arrays": [[np.array(g) for g in p] for p in tuples],
    }
    for form, partitions in forms.items():
        record_evaluation(tmp_path / f"{form}.rrd", frames, {"d": partitions}, name="same")
    assert content(tmp_path / "lists.rrd") == content(tmp_path / "tuples.rrd")
    assert content(tmp_path / "arrays.rrd") == content(tmp_path / "tuples.rrd")


def test_bad_partitions_and_evaluations_are_named(tmp_path):
    frames = make_frames(4)
    bad = alternating_detector(frames)
    bad[1] = ((0, 1), (), (2, 3, 4, 5, ROBOT_ID))
    with pytest.raises(ValueError, match=r"d partitions\[1\] \(sequence 'episode', time 0\.1 s\)"):
        record_evaluation(tmp_path / "a.rrd", frames, {"d": bad})
    good = alternating_detector(frames)
    other = evaluate(frames, Majority().predict(frames))
    with pytest.raises(ValueError, match="evaluation does not belong to these frames"):
        record_evaluation(tmp_path / "a.rrd", frames, {"d": good}, {"d": other})
    assert not (tmp_path / "a.rrd").exists()


# ----------------------------------------------------------------------------- MuJoCo scene

SCENE_XML = """
<mujoco>
  <asset><mesh name="tet" vertex="0 0 0  1 0 0  0 1 0  0 0 1"/></asset>
  <worldbody>
    <geom name="floor" type="plane" size="3 2 0.1" rgba="0.2 0.3 0.4 1"/>
    <geom name="wall" type="box" pos="0 2 1" size="3 0.05 1"/>
    <geom name="ghost" type="box" size="1 1 1" rgba="1 1 1 0"/>
    <body name="person/1" pos="1 0 0" mocap="true">
      <geom name="torso" type="capsule" fromto="0 0 0.3 0 0 1.4" size="0.2" rgba="1 0 0 1"/>
      <geom name="head" type="sphere" pos="0 0 1.6" size="0.12"/>
    </body>
    <body name="robot" pos="-1 0 0">
      <geom name="base" type="cylinder" pos="0 0 0.3" size="0.25 0.3"/>
      <geom name="belly" type="ellipsoid" pos="0 0 0.8" size="0.2 0.15 0.25"/>
      <geom name="arm" type="capsule" fromto="0 0 1 0.5 0 1" size="0.05"/>
      <geom name="badge" type="mesh" mesh="tet" pos="0 0.2 1"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_model_geometry_is_logged_per_body_and_type(tmp_path):
    model = mujoco.MjModel.from_xml_string(SCENE_XML)
    path = tmp_path / "scene.rrd"
    with open_recording(path, name="scene") as rec:
        counts = log_model(rec, model)
    assert counts == {
        "capsules": 2,
        "boxes": 1,
        "spheres": 2,
        "cylinders": 1,
        "planes": 1,
        "meshes": 1,
        "skipped": 0,
    }
    rec = Recording(path)
    person = "/" + body_entity(model, 1)
    assert person == "/world/model/person_1"
    assert {
        "/world/model/world/planes",
        "/world/model/world/boxes",
        f"{person}/capsules",
        f"{person}/spheres",
        "/world/model/robot/cylinders",
        "/world/model/robot/spheres",
        "/world/model/robot/capsules",
        "/world/model/robot/meshes/0",
    } <= rec.entities
    np.testing.assert_allclose(rec.static[person]["Transform3D:translation"], [[1, 0, 0]])
    np.testing.assert_allclose(
        rec.static["/world/model/world/planes"]["Boxes3D:half_sizes"], [[3, 2, 0]]
    )
    np.testing.assert_allclose(
        rec.static["/world/model/world/boxes"]["Boxes3D:half_sizes"], [[3, 0.05, 1]]
    )
    # A capsule from fromto: its end-cap centres are the fromto points (in the body frame).
    arm = rec.static["/world/model/robot/capsules"]
    start = np.array(arm["Capsules3D:translations"][0])
    axis = _rotate_xyzw(
        arm["Capsules3D:quaternions"][0], np.array([0.0, 0.0, arm["Capsules3D:lengths"][0]])
    )
    ends = sorted([tuple(np.round(start, 6)), tuple(np.round(start + axis, 6))])
    np.testing.assert_allclose(ends, [(0, 0, 1), (0.5, 0, 1)], atol=1e-6)
    torso = rec.static[f"{person}/capsules"]
    np.testing.assert_allclose(torso["Capsules3D:radii"], [0.2])
    assert torso["Capsules3D:colors"] == [0xFF0000FF]
    mesh = rec.static["/world/model/robot/meshes/0"]
    np.testing.assert_allclose(
        np.array(mesh["Mesh3D:vertex_positions"]).min(axis=0), [0, 0.2, 1], atol=1e-6
    )


def _rotate_xyzw(q, v):
    x, y, z, w = q
    u = np.array([x, y, z])
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def test_body_poses_move_bodies_per_frame(tmp_path):
    model = mujoco.MjModel.from_xml_string(SCENE_XML)
    data = mujoco.MjData(model)
    times, xpos, xquat = [], [], []
    for t in range(5):
        data.mocap_pos[0] = [1 + 0.1 * t, 0.2 * t, 0]
        yaw = 0.3 * t
        data.mocap_quat[0] = [math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]
        mujoco.mj_kinematics(model, data)
        times.append(0.1 * t)
        xpos.append(data.xpos.copy())
        xquat.append(data.xquat.copy())
    poses = BodyPoses(time=times, position=np.array(xpos), quaternion=np.array(xquat))
    path = tmp_path / "poses.rrd"
    with open_recording(path, name="poses") as rec:
        log_model(rec, model, static_poses=False)
        moving = log_body_poses(rec, model, poses)
    assert moving == 1
    rec = Recording(path)
    person = "/world/model/person_1"
    assert rec.frames(person) == [0, 1, 2, 3, 4]
    translations = np.array(rec.column(person, "Transform3D:translation"))[:, 0]
    np.testing.assert_allclose(translations, np.array(xpos)[:, 1], atol=1e-6)
    quats = np.array(rec.column(person, "Transform3D:quaternion"))[:, 0]
    np.testing.assert_allclose(
        quats, np.array(xquat)[:, 1][:, [1, 2, 3, 0]], atol=1e-6
    )  # (x, y, z, w)
    np.testing.assert_allclose(
        rec.static["/world/model/robot"]["Transform3D:translation"], [[-1, 0, 0]]
    )
    with pytest.raises(ValueError, match=r"poses must hold the model's 3 bodies, got 2"):
        log_body_poses(
            None,
            model,
            BodyPoses(time=[0.0], position=np.zeros((1, 2, 3)), quaternion=np.zeros((1, 2, 4))),
        )


def test_episode_with_a_model_draws_its_geometry_instead_of_capsules(tmp_path):
    model = mujoco.MjModel.from_xml_string(SCENE_XML)
    frames = make_frames(3)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    poses = BodyPoses(
        time=[f.time for f in frames],
        position=np.repeat(data.xpos[None], 3, axis=0) + np.arange(3)[:, None, None] * 0.1,
        quaternion=np.repeat(data.xquat[None], 3, axis=0),
        sequence="episode",
    )
    path = tmp_path / "model.rrd"
    record_episode(path, frames, model=model, body_poses=poses, seed=1)
    rec = Recording(path)
    assert "/world/people/bodies" not in rec.entities
    assert "/world/room/floor" not in rec.entities
    assert rec.frames("/world/model/robot") == [0, 1, 2]
    assert "/world/model/world/planes" in rec.static


def test_head_camera_images_are_logged_as_jpeg_per_frame(tmp_path):
    from io import BytesIO

    from PIL import Image

    frames = make_frames(4)
    y, x = np.mgrid[0:48, 0:64]
    images = np.stack(
        [np.stack([x * 4, y * 5, np.full_like(x, 40 * k)], axis=-1) for k in range(3)]
    ).astype(np.uint8)
    camera = CameraImages(time=[f.time for f in frames[1:]], images=images, sequence="episode")
    path = tmp_path / "camera.rrd"
    record_episode(path, frames, cameras=[camera])
    rec = Recording(path)
    assert rec.frames("/camera/head") == [1, 2, 3]
    assert rec.static["/camera/head"]["EncodedImage:media_type"] == ["image/jpeg"]
    for k, blob in enumerate(rec.column("/camera/head", "EncodedImage:blob")):
        decoded = np.asarray(Image.open(BytesIO(bytes(blob[0]))))
        assert decoded.shape == (48, 64, 3)
        assert np.abs(decoded.astype(int) - images[k]).mean() < 3.0  # JPEG, quality 85
    with pytest.raises(ValueError, match=r"images\[0\] must be an \(height, width, 3\) uint8"):
        CameraImages(time=[0.0], images=np.zeros((1, 4, 4), dtype=np.uint8))


# ----------------------------------------------------------------------------- dataset views


def test_dataset_views_characterisation_pairs_regions_and_stress(tmp_path):
    from sklearn.linear_model import LogisticRegression

    from reform import characterise

    frames = [f for f in make_frames(40) if f.groups is not None]
    distance, effort, label = pair_scatter_data(frames)
    classifier = LogisticRegression().fit(np.column_stack([distance, effort]), label)
    path = tmp_path / "dataset.rrd"
    with open_recording(
        path,
        name="dataset",
        blueprint=default_blueprint(characterisation=["toy"], pairs=["toy"], stress=["noise"]),
    ) as rec:
        shapes = log_characterisation(rec, frames, name="toy")
        log_pair_scatter(rec, distance, effort, label, name="toy", classifier=classifier)
        log_stress_curves(
            rec,
            [0.0, 0.1, 0.2],
            {"reform F1": [0.9, 0.8, 0.6], "gcff F1": [0.7, 0.6, 0.5]},
            x_label="noise (m)",
            name="noise",
        )
    rec = Recording(path)
    means = characterise(frames).mean_by_size()
    assert shapes.mean_by_size() == means
    tight = rec.static["/dataset/characterisation/toy/tightness"]
    np.testing.assert_allclose(
        _tensor(tight["BarChart:values"]), [means[s][0] for s in sorted(means)]
    )
    np.testing.assert_allclose(_tensor(tight["BarChart:abscissa"]), sorted(means))
    sym = rec.static["/dataset/characterisation/toy/symmetry"]
    np.testing.assert_allclose(
        _tensor(sym["BarChart:values"]), [means[s][1] for s in sorted(means)]
    )
    assert "| 3 |" in rec.static["/dataset/characterisation/toy/table"]["TextDocument:text"][0]
    points = rec.static["/dataset/pairs/toy/points"]
    np.testing.assert_allclose(
        np.array(points["Points2D:positions"]), np.column_stack([distance, effort]), atol=1e-5
    )
    assert points["Points2D:class_ids"] == label.tolist()
    image = rec.static["/dataset/pairs/toy/regions"]
    assert "Image:buffer" in image
    stress = rec.static["/dataset/stress/noise/reform_F1"]
    np.testing.assert_allclose(_tensor(stress["BarChart:values"]), [0.9, 0.8, 0.6])
    # two curves side by side: bars 0.04 wide (80% of the 0.1 gap, halved), either side of x
    np.testing.assert_allclose(_tensor(stress["BarChart:abscissa"]), [-0.02, 0.08, 0.18])
    gcff = rec.static["/dataset/stress/noise/gcff_F1"]
    np.testing.assert_allclose(_tensor(gcff["BarChart:abscissa"]), [0.02, 0.12, 0.22])
    np.testing.assert_allclose(gcff["BarChart:widths"], [0.04] * 3)


def _tensor(value) -> np.ndarray:
    """A logged tensor (BarChart values) as a flat array."""
    if isinstance(value, list) and len(value) == 1 and isinstance(value[0], dict):
        value = value[0]
    if isinstance(value, dict):
        buffer = value["buffer"]
        if isinstance(buffer, tuple):
            buffer = buffer[1]
        return np.asarray(buffer, dtype=np.float64).ravel()
    return np.asarray(value, dtype=np.float64).ravel()


def test_decision_regions_follow_the_classifier(tmp_path):
    # P(together) = 1 below 1 m, else 0: the left of the image is "together", the right "apart".
    path = tmp_path / "regions.rrd"
    with open_recording(path, name="regions") as rec:
        log_pair_scatter(
            rec,
            [0.5, 1.5, 2.0],
            [0.1, 3.0, 6.0],
            [1, 0, 0],
            name="rule",
            classifier=lambda x: (x[:, 0] < 1.0).astype(float),
            max_distance_m=2.0,
        )
    reader = RrdReader(path)
    chunk = next(
        c
        for c in reader.stream()
        if c.entity_path == "/dataset/pairs/rule/regions"
        and "Image:buffer" in c.to_record_batch().schema.names
    )
    data = chunk.to_record_batch().to_pydict()
    pixels = np.frombuffer(bytes(data["Image:buffer"][0][0]), dtype=np.uint8).reshape(160, 160, 4)
    assert tuple(pixels[0, 0, :3]) == (240, 140, 40)  # together
    assert tuple(pixels[0, -1, :3]) == (80, 120, 200)  # apart
    assert tuple(pixels[-1, 79, :3]) == (240, 140, 40) and tuple(pixels[-1, 80, :3]) == (
        80,
        120,
        200,
    )
    transform = Recording(path).static["/dataset/pairs/rule/regions"]
    np.testing.assert_allclose(
        transform["Transform3D:scale"], [[2.0 / 160, 2 * math.pi / 160, 1.0]]
    )


# ----------------------------------------------------------------------------- real data


def test_evaluation_recording_of_real_salsa_frames(tmp_path, salsa_dataset):
    frames = salsa_dataset.annotated()[:12]
    predictions = Majority().fit(frames).predict(frames)
    evaluation = evaluate(frames, predictions)
    path = tmp_path / "salsa.rrd"
    record_evaluation(
        path,
        frames,
        {"majority": predictions},
        {"majority": evaluation},
        name="salsa",
        dataset="salsa",
    )
    rec = Recording(path)
    assert rec.frames("/world/people/labels") == list(range(12))
    for t, frame in enumerate(frames):
        row = rec.rows["/world/groups/truth/members"][t]
        assert sorted(row["person_id"]) == sorted(frame.ids.tolist())
        np.testing.assert_allclose(
            np.array(rec.rows["/world/people/labels"][t]["Points3D:positions"])[:, :2],
            frame.position,
            atol=1e-5,
        )
    final = rec.column("/metrics/f1/majority", "Scalars:scalars")[-1][0]
    assert final == pytest.approx(evaluation.at("2/3").f1)
    assert "/dataset/characterisation/salsa/tightness" in rec.static
    assert len(rec.static["/dataset/pairs/salsa/points"]["Points2D:positions"]) == sum(
        f.n_people * (f.n_people - 1) // 2 for f in frames
    )


# ----------------------------------------------------------------------------- targets and errors


def test_command_line_flags_follow_rerun_conventions(tmp_path):
    parser = argparse.ArgumentParser()
    add_recording_arguments(parser)
    assert target_from_args(parser.parse_args([])) is None
    target = target_from_args(parser.parse_args(["--save", str(tmp_path / "x.rrd")]))
    assert target == RecordingTarget(save=tmp_path / "x.rrd")
    target = target_from_args(
        parser.parse_args(["--connect", "--url", "rerun+http://127.0.0.1:9999/proxy"])
    )
    assert target.connect == "rerun+http://127.0.0.1:9999/proxy" and target.save is None
    assert target_from_args(parser.parse_args(["--connect"])).connect == ""
    assert target_from_args(parser.parse_args(["--serve"])).serve
    with pytest.raises(ValueError, match="--url needs --connect"):
        target_from_args(parser.parse_args(["--url", "rerun+http://127.0.0.1:9999/proxy"]))
    with pytest.raises(ValueError, match=r"save must be a path ending in \.rrd, got '.*run\.txt'"):
        RecordingTarget(save=tmp_path / "run.txt")
    with pytest.raises(ValueError, match="needs save, connect or serve"):
        RecordingTarget()


def test_the_viewer_program_is_started_itself_on_this_machine_only(tmp_path):
    from listening import free_port, listening_hosts, supported

    from sim.recording import rerun_program, stop_viewer, viewer_command

    program = rerun_program()
    assert not program.read_bytes()[:2] == b"#!"  # the program, not the script that runs it
    port = free_port()
    command = viewer_command("--port", str(port), "--save", str(tmp_path / "got.rrd"))
    assert command[:3] == [str(program), "--bind", "127.0.0.1"]
    viewer = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(200):
            if not supported() or listening_hosts(port):
                break
            time.sleep(0.05)
        if supported():
            assert listening_hosts(port) == {"127.0.0.1"}
    finally:
        stop_viewer(viewer)
    assert viewer.poll() is not None  # stopped: nothing left running


def test_the_rerun_command_printed_is_one_this_shell_runs(tmp_path, monkeypatch):
    from sim.recording import rerun_in_this_shell

    mine = Path(sys.executable).with_name("rerun")
    clone = mine.parents[2]  # the folder holding the environment, as a clone holds .venv
    monkeypatch.setenv("PATH", str(tmp_path))  # a new shell: the environment not activated
    monkeypatch.chdir(clone)
    typed = rerun_in_this_shell()
    assert typed == str(mine.relative_to(clone))  # .venv/bin/rerun
    assert subprocess.run([typed, "--version"], capture_output=True).returncode == 0
    monkeypatch.chdir(tmp_path)
    assert rerun_in_this_shell() == str(mine)
    monkeypatch.setenv("PATH", str(mine.parent))  # activated
    assert rerun_in_this_shell() == "rerun"


@pytest.mark.skipif(sys.platform == "win32", reason="stops the run with SIGINT")
def test_serve_listens_on_this_machine_only_until_ctrl_c(tmp_path):
    from listening import listening_hosts, supported

    from sim.recording._program import VIEWER_STOP_S
    from sim.recording._target import SERVE_GRPC_PORT, SERVE_WEB_PORT

    if not supported():
        pytest.skip("reads the listening addresses from Linux /proc/net")
    if listening_hosts(SERVE_GRPC_PORT) or listening_hosts(SERVE_WEB_PORT):
        pytest.skip(f"port {SERVE_GRPC_PORT} or {SERVE_WEB_PORT} is in use on this machine")
    run = subprocess.Popen(
        [str(REFORM_SIM), "simulate", "--scenario", "hri-conversation", "--duration", "1"]
        + ["--out", str(tmp_path / "x.parquet"), "--serve", "--quiet"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = run.stderr.readline()
        assert line.startswith(
            f"serving the recording at rerun+http://127.0.0.1:{SERVE_GRPC_PORT}/proxy"
        ), line
        assert listening_hosts(SERVE_GRPC_PORT) == {"127.0.0.1"}
        assert listening_hosts(SERVE_WEB_PORT) == {"127.0.0.1"}
        run.send_signal(signal.SIGINT)  # the run only: it stops the web viewer itself
        # The web viewer is stopped, not left to be killed after VIEWER_STOP_S.
        _, rest = run.communicate(timeout=VIEWER_STOP_S / 2)
        assert run.returncode == 0, rest
    finally:
        if run.poll() is None:
            run.kill()
            run.wait()
    assert "stopped serving" in rest
    assert not listening_hosts(SERVE_GRPC_PORT) and not listening_hosts(SERVE_WEB_PORT)


def test_a_failed_run_leaves_no_file(tmp_path):
    path = tmp_path / "broken.rrd"
    with pytest.raises(RuntimeError, match="boom"), open_recording(path, name="broken") as rec:
        rec.log("world/x", rr.Points3D([[0, 0, 0]]), static=True)
        raise RuntimeError("boom")
    assert not path.exists() and list(tmp_path.iterdir()) == []


def test_bad_inputs_are_named(tmp_path):
    frames = make_frames(4)
    bad = alternating_detector(frames)
    bad[2] = ((0, 1), (2,))  # people 3, 4, 5 and the robot missing
    with pytest.raises(
        ValueError,
        match=r"reform partitions\[2\] \(sequence 'episode', time 0\.2 s\): person 3 is in no ",
    ):
        record_evaluation(tmp_path / "a.rrd", frames, {"reform": bad})
    bad[2] = ((0, 1, 1),)
    with pytest.raises(ValueError, match=r"person 1 \(group 0\) appears twice"):
        record_evaluation(tmp_path / "a.rrd", frames, {"reform": bad})
    with pytest.raises(ValueError, match="must hold one partition per frame: expected 4, found 3"):
        record_evaluation(tmp_path / "a.rrd", frames, {"reform": bad[:3]})
    stray = [frames[0].replace(time=9.0)]
    with pytest.raises(
        ValueError,
        match=r"observed\[0\] \(sequence 'episode', time 9 s\) matches no frame of the run",
    ):
        record_episode(tmp_path / "b.rrd", frames, observed=stray)
    with pytest.raises(
        ValueError,
        match=r"frames\[1\] \(sequence 'episode'\) has time 0 s, before the previous frame's 0\.3",
    ):
        Clock.from_frames([frames[3], frames[0]])
    with pytest.raises(ValueError, match="detector names must be .* not 'truth'; got 'truth'"):
        record_episode(tmp_path / "c.rrd", frames, detections={"truth": bad})
    with pytest.raises(ValueError, match=r"horizontal_deg must be in \(0, 360\], got 0"):
        FieldOfView(horizontal_deg=0)
    with pytest.raises(
        ValueError, match=r"label must hold 0 \(apart\) or 1 \(together\), got \[0, 2\]"
    ):
        with open_recording(tmp_path / "d.rrd", name="d") as rec:
            log_pair_scatter(rec, [1.0, 2.0], [0.0, 1.0], [0, 2], name="x")
    assert not (tmp_path / "a.rrd").exists()


def test_logging_functions_compose_on_one_stream(tmp_path):
    frames = make_frames(5)
    path = tmp_path / "pieces.rrd"
    with open_recording(path, name="pieces", seed=3) as rec:
        clock = log_frames(rec, frames, field_of_view=None, trail_s=0)
        truth = log_groups(rec, frames, clock=clock)
        log_groups(
            rec, frames, alternating_detector(frames), name="reform", clock=clock, truth=truth
        )
    rec = Recording(path)
    assert "/world/robot/field_of_view" not in rec.entities
    assert "/world/people/trails" not in rec.entities
    assert rec.frames("/world/groups/reform/members") == list(range(5))
    assert rec.recording_id == recording_id("pieces", seed=3)


# ----------------------------------------------------------------------------- the commands


@pytest.mark.parametrize("command", ["evaluate", "detect"])
def test_commands_save_a_recording(tmp_path, capsys, command):
    from reform import Dataset
    from reform.datasets import write_parquet
    from sim.cli import main

    frames = make_frames(8)
    data = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(frames), name="toy"), data)
    path = tmp_path / "out" / f"{command}.rrd"
    extra = ["--out", tmp_path / "detections.json"] if command == "detect" else []
    status = main(
        [
            str(a)
            for a in [command, "--detector", "majority", "--data", data, *extra, "--save", path]
        ]
    )
    assert status == 0
    assert f"wrote {path}" in capsys.readouterr().err
    rec = Recording(path)
    assert rec.recording_id == recording_id(f"{command}-majority-toy")
    n = 8 if command == "detect" else sum(f.groups is not None for f in frames)
    assert rec.frames("/world/groups/majority/members") == list(range(n))
    assert "/dataset/characterisation/toy/tightness" in rec.static
    status = main(
        [command, "--detector", "majority", "--data", str(data), *map(str, extra), "--url", "x"]
    )
    assert status == 2 and "--url needs --connect" in capsys.readouterr().err


def test_a_truth_naming_someone_absent_is_drawn_and_scored_as_the_evaluation_scores_it(tmp_path):
    # The annotation lists (1, 9) with 9 not in the frame (a pose the tracker lost): drawn, the
    # truth is the people present; scored, the evaluation counts the group as listed.
    frame = Frame(
        ids=[1, 2, 3, 4],
        position=[[0, 0], [3, 0], [3.8, 0], [8, 0]],
        yaw=[0.0, 0.0, math.pi, 0.0],
        groups=((1,), (2, 3), (4,)),
        listed_groups=((1, 9), (2, 3)),
        sequence="s",
    )
    prediction = ((1,), (2, 3), (4,))
    evaluation = evaluate([frame], [prediction])
    assert evaluation.at("2/3").recall == 0.5
    path = tmp_path / "absent.rrd"
    record_evaluation(path, [frame], {"gcff": [prediction]}, {"gcff": evaluation})
    rec = Recording(path)
    assert rec.rows["/world/groups/truth/members"][0]["person_id"] == [1, 2, 3, 4]
    mistakes = "/world/groups/gcff/mistakes"
    assert rec.rows[f"{mistakes}/missed"][0]["Cylinders3D:labels"] == []  # (2, 3) found, as drawn
    assert rec.rows[f"{mistakes}/spurious"][0]["Cylinders3D:labels"] == []
    final = rec.column("/metrics/f1/gcff", "Scalars:scalars")[-1][0]
    assert final == pytest.approx(evaluation.at("2/3").f1)

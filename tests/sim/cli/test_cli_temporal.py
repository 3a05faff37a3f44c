"""``evaluate --temporal``: the group events of a detector's answers scored against the truth's
(reform.evaluate_events), in the printed report and the JSON; refused in one line, before any
detector runs, where the frames cannot be scored in time."""

from __future__ import annotations

import json

import pytest
from cli_errors import cli_error
from toy_scenes import line_frame, toy_frames

from reform import Dataset, Frame, make_detector, write_parquet
from reform.seeding import Role, derive_rng
from reform.temporal import evaluate_events
from sim.cli import main


def sequence_frames() -> tuple[Frame, ...]:
    """Two sequences of five people, 0.5 s apart: person 3 joins (1, 2) at 2 s and leaves at
    4 s; (4, 5) form at 1 s in sequence b."""
    frames = []
    for sequence in ("a", "b"):
        for k in range(12):
            t = 0.5 * k
            groups = [[1, 2, 3]] if 2.0 <= t < 4.0 else [[1, 2]]
            if sequence == "b" and t >= 1.0:
                groups.append([4, 5])
            frames.append(line_frame([1, 2, 3, 4, 5], groups, time=t, sequence=sequence))
    return tuple(frames)


@pytest.fixture
def toy_dataset(tmp_path):
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=sequence_frames(), name="toy", source="toy_scenes"), path)
    return path


@pytest.mark.parametrize("detector", ["gcff", "majority"])
def test_the_report_holds_the_detectors_events_in_time(detector, toy_dataset, tmp_path, capsys):
    argv = ["evaluate", "--detector", detector, "--data", toy_dataset, "--temporal"]
    assert main([str(a) for a in [*argv, "--out", tmp_path]]) == 0
    printed = capsys.readouterr().out
    assert "Groups in time:" in printed and "within 1 s" in " ".join(printed.split())
    temporal = json.loads((tmp_path / "evaluation.json").read_text())["temporal"]
    frames = sequence_frames()
    unlabelled = [f.replace(groups=None) for f in frames]
    expected = evaluate_events(
        frames,
        make_detector(detector).predict(unlabelled),
        tolerance_s=1.0,
        rng=derive_rng(0, Role.TEMPORAL_BOOTSTRAP),
    ).to_json()
    assert temporal == json.loads(json.dumps(expected))
    assert temporal["true_events"] > 0
    if detector == "majority":  # everyone alone: no event found, none invented
        assert (temporal["recall"], temporal["false_events"]) == (0.0, 0)


def test_the_tolerance_defaults_to_the_frame_interval_where_longer(tmp_path, capsys):
    frames = [f.replace(time=3.0 * f.time) for f in sequence_frames()]  # 1.5 s apart
    path = tmp_path / "slow.parquet"
    write_parquet(Dataset(frames=tuple(frames), name="slow", source="toy_scenes"), path)
    argv = ["evaluate", "--detector", "gcff", "--data", path, "--temporal", "--out", tmp_path]
    assert main([str(a) for a in argv]) == 0
    assert json.loads((tmp_path / "evaluation.json").read_text())["temporal"]["tolerance_s"] == 1.5


def test_refusals_name_the_sequence_and_come_before_any_detector(toy_dataset, tmp_path, capsys):
    argv = ["evaluate", "--detector", "gcff", "--data", toy_dataset]
    assert cli_error([*argv, "--tolerance", "2"], capsys) == (
        "reform-sim evaluate: error: --tolerance is the matching window of --temporal; give "
        "--temporal too"
    )
    err = cli_error([*argv, "--temporal", "--tolerance", "0.2"], capsys)
    assert err.startswith(f"reform-sim evaluate: error: --temporal: {toy_dataset}: tolerance_s ")
    assert "sequence 'a'" in err and "expected >= 0.5 s" in err and "got 0.2 s" in err
    one = tmp_path / "one.parquet"
    frame = sequence_frames()[0]
    write_parquet(Dataset(frames=(frame,), name="one", source="toy_scenes"), one)
    err = cli_error(["evaluate", "--detector", "gcff", "--data", one, "--temporal"], capsys)
    assert err.startswith(f"reform-sim evaluate: error: --temporal: {one}: ")
    assert "sequence 'a'" in err


def test_a_detector_that_never_changes_its_answer_invents_no_event(tmp_path, capsys):
    frames = tuple(f.replace(time=float(k)) for k, f in enumerate(toy_frames(2, 10)))
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=frames, name="toy", source="toy_scenes"), path)
    argv = ["evaluate", "--detector", "majority", "--data", path, "--temporal", "--out", tmp_path]
    assert main([str(a) for a in argv]) == 0
    temporal = json.loads((tmp_path / "evaluation.json").read_text())["temporal"]
    assert temporal["detected_events"] == 0 and temporal["false_events_per_minute"] == 0.0


def test_data_info_counts_the_group_events(toy_dataset, capsys):
    from collections import Counter

    from reform import group_events

    assert main(["data", "info", "--data", str(toy_dataset), "--json"]) == 0
    counts = json.loads(capsys.readouterr().out)["group_events"]
    expected = Counter(e.kind for e in group_events(sequence_frames()))
    assert counts == {kind: expected.get(kind, 0) for kind in counts}
    assert counts["joins"] == 2 and counts["leaves"] == 2 and counts["forms"] == 1
    assert main(["data", "info", "--data", str(toy_dataset)]) == 0
    assert "group events     1 forms, 0 dissolves, 2 joins, 2 leaves" in capsys.readouterr().out

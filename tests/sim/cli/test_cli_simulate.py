"""``reform-sim simulate`` and ``reform-sim scenarios``: files written, read back; bad input."""

from __future__ import annotations

import json
import re

import numpy as np
import pyarrow.parquet as pq
import pytest
import tqdm  # noqa: F401 - imported before the memory of a refusal is traced
from rerun.chunk import RrdReader
from traced import traced_peak

import scenarios
import sim.episode
import sim.recording  # noqa: F401 - imported before the memory of a refusal is traced
from reform.datasets import read_parquet
from sim.cli import main
from sim.episode import simulate_episode


def test_simulate_writes_the_episode_as_parquet(tmp_path, capsys):
    out = tmp_path / "run" / "conversation.parquet"
    argv = ["simulate", "--scenario", "hri-conversation", "--seed", "3", "--out", str(out)]
    assert main([*argv, "--set", "talk_duration=8", "--duration", "12"]) == 0
    written = read_parquet(out)
    expected = simulate_episode(
        "hri-conversation", seed=3, duration=12.0, options={"talk_duration": 8.0}
    )
    assert list(written) == list(expected.dataset)
    assert written.metadata["scenario"] == "hri-conversation"
    assert written.metadata["options"]["talk_duration"] == 8.0
    printed = capsys.readouterr().out
    assert "24 frames of hri-conversation (seed 3, 12 s at 2 Hz, view truth)" in printed


def test_simulate_robot_view_with_sensor_options(tmp_path):
    out = tmp_path / "seen.parquet"
    code = main(
        [
            "simulate",
            "--scenario",
            "word-improv",
            "--seed",
            "2",
            "--duration",
            "10",
            "--rate",
            "1",
            "--view",
            "robot",
            "--set",
            "robot=watch",
            "--set",
            "players=3",
            "--dropout",
            "0.5",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    written = read_parquet(out)
    assert len(written) == 10
    assert written.metadata["view"] == "robot"
    assert written.metadata["sensor"]["dropout"] == 0.5
    assert all(0 in f.ids for f in written)
    assert any(f.n_people < 5 for f in written)


def test_simulate_save_records_the_episode(tmp_path):
    out, rrd = tmp_path / "c.parquet", tmp_path / "c.rrd"
    argv = ["simulate", "--scenario", "hri-conversation", "--seed", "1", "--out", str(out)]
    assert main([*argv, "--save", str(rrd)]) == 0
    texts: dict[str, list[str]] = {"/events": [], "/events/truth": []}
    entities = set()
    for chunk in RrdReader(rrd).stream():
        entities.add(chunk.entity_path)
        if chunk.entity_path in texts:
            column = chunk.to_record_batch().column("TextLog:text").to_pylist()
            texts[chunk.entity_path] += [t[0] for t in column]
    assert {
        "/world/people/bodies",
        "/world/robot/bodies",
        "/world/groups/truth/members",
    } <= entities
    scenario, truth = texts["/events"], texts["/events/truth"]
    assert any(t.startswith("approach:") for t in scenario)
    assert any(t.startswith("leave:") for t in scenario)
    assert any("forms" in t for t in truth)  # the group events of the ground truth


def test_simulate_save_draws_the_sensors_own_field_of_view(tmp_path):
    """The wedge in the recording is the sensor the frames were observed with."""
    out, rrd = tmp_path / "seen.parquet", tmp_path / "seen.rrd"
    argv = ["simulate", "--scenario", "hri-conversation", "--seed", "1", "--duration", "4"]
    sensor = ["--view", "robot", "--fov-deg", "90", "--min-range", "0.3", "--max-range", "3"]
    assert main([*argv, *sensor, "--out", str(out), "--save", str(rrd)]) == 0
    batches = [
        chunk.to_record_batch()
        for chunk in RrdReader(rrd).stream()
        if chunk.entity_path == "/world/robot/field_of_view"
    ]
    wedges = [
        strip
        for batch in batches
        if "LineStrips3D:strips" in batch.schema.names
        for row in batch.column("LineStrips3D:strips").to_pylist()
        for strip in row
    ]
    assert wedges
    first = read_parquet(out).frames[0]
    robot = int(np.flatnonzero(first.is_robot)[0])
    apex = first.head_position[robot] if first.head_position is not None else first.position[robot]
    reach = np.linalg.norm(np.array(wedges[0])[:, :2] - apex, axis=1)
    assert reach.max() == pytest.approx(3.0, rel=1e-5)
    assert reach.min() == pytest.approx(0.3, rel=1e-5)
    # The far arc spans 90 degrees as seen from the robot's head.
    far = np.array(wedges[0])[:, :2] - apex
    far = far[np.isclose(np.linalg.norm(far, axis=1), 3.0, rtol=1e-5)]
    middle = far.mean(axis=0)
    bearings = np.arctan2(far[:, 1], far[:, 0]) - np.arctan2(middle[1], middle[0])
    bearings = (bearings + np.pi) % (2 * np.pi) - np.pi
    assert np.degrees(np.ptp(bearings)) == pytest.approx(90.0, abs=1e-3)


def test_field_of_view_defaults_are_the_sensors():
    from sim.recording import FieldOfView
    from sim.sensor import Sensor

    assert FieldOfView() == FieldOfView.of(Sensor()) == FieldOfView.of(None)
    assert FieldOfView.of(Sensor(fov_deg=120.0, max_range=6.0)) == FieldOfView(120.0, 0.5, 6.0)


def test_scenarios_lists_names_and_typed_options(capsys):
    assert main(["scenarios"]) == 0
    text = capsys.readouterr().out
    for name in scenarios.names():
        assert f"\n{name}: " in "\n" + text
    assert "players" in text and "{none,watch,moderate}" in text and "= 6" in text
    assert main(["scenarios", "mingle", "--json"]) == 0
    (entry,) = json.loads(capsys.readouterr().out)
    options = {o["name"]: o for o in entry["options"]}
    assert entry["name"] == "mingle" and options["people"] == {
        "name": "people",
        "type": "int",
        "choices": None,
        "default": 18,
        "help": "guests (2-100).",
    }


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--scenario", "dance"], r"unknown scenario 'dance'; known scenarios: .*hri-conversation"),
        (["--set", "players=1"], r"word-improv: option players must be within \[2, 7\], got 1"),
        (["--set", "players"], r"--set must be KEY=VALUE, got 'players'"),
        (["--set", "players=many"], r"option players must be an integer, got 'many'"),
        (["--duration", "-5"], r"duration must be a positive number of seconds, got -5.0"),
        (["--dropout", "0.1"], r"sensor options need --view robot, got --dropout"),
        (
            ["--view", "robot"],
            r'view="robot" needs a robot, and scenario word-improv has none with these options '
            r"\(robot=watch puts it there\)",
        ),
    ],
)
def test_simulate_bad_input_fails_before_any_work(tmp_path, capsys, extra, match):
    out = tmp_path / "never.parquet"
    scenario = [] if "--scenario" in extra else ["--scenario", "word-improv"]  # one of each
    argv = ["simulate", *scenario, "--seed", "1", "--out", str(out), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("reform-sim simulate: error: ")
    assert re.search(match, err), err
    assert not out.exists()


def test_simulate_refuses_other_outputs(tmp_path, capsys):
    argv = ["simulate", "--scenario", "mingle", "--seed", "1", "--out"]
    assert main([*argv, str(tmp_path / "frames.csv")]) == 2
    assert "--out must name a .parquet file, got" in capsys.readouterr().err


def test_calibrate_bad_input(tmp_path, capsys):
    assert main(["calibrate", "--out", str(tmp_path), "--data", str(tmp_path)]) == 2
    assert f"--data {tmp_path}: expected one of salsa, babble" in capsys.readouterr().err
    (tmp_path / "salsa").mkdir()
    assert main(["calibrate", "--out", str(tmp_path), "--data", str(tmp_path)]) == 2
    assert f"babble not found ({tmp_path / 'babble'}: no such file" in capsys.readouterr().err
    assert main(["calibrate", "--out", str(tmp_path), "--episodes", "0"]) == 2
    assert "--episodes must be >= 1, got 0" in capsys.readouterr().err


def test_calibrate_reads_the_datasets_named_by_the_environment(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "elsewhere"))
    assert main(["calibrate", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "salsa not found" in err and "reform-sim datasets fetch salsa" in err


# --------------------------------------------------------------------------------------------
# Requests sized before they run (sim.sizing)

REFUSAL_PEAK_BYTES = 50 * 2**20  # bytes: what a refused request may allocate while refused
SHRINK = r"ask for less \(a shorter --duration, a lower --rate or a larger --dt\)"


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (
            ["--duration", "1e9"],
            r"the run writes about [\d.]+ TiB \(2,000,000,000 frames of 18 agents\), more than "
            r"the 100 GiB free where --out \S+never.parquet is; " + SHRINK + " or write elsewhere",
        ),
        (
            ["--duration", "1e9", "--save", "REC"],
            r"the run needs about [\d.]+ TiB of memory \(2,000,000,000 frames of 18 agents held "
            r"in memory\), more than the 16 GiB of memory this machine has available; "
            + SHRINK
            + r", record nothing \(no --save, --connect, --serve\) to stream the frames to --out "
            r"in bounded memory, or change the limit with --max-memory SIZE \(e.g. 64G\)",
        ),
        (
            ["--dt", "1e-12"],
            r"the run needs about 3.64 TiB of memory \(the world's schedule of "
            r"500,000,000,000 control steps per frame\), more than the 16 GiB of memory this "
            r"machine has available; " + SHRINK + r", or change the limit with --max-memory SIZE "
            r"\(e.g. 64G\)",
        ),
        (
            ["--dt", "1e-9"],
            r"the run would take about [\d.]+ days on this machine \(1,200 frames of 18 agents\), "
            r"more than the 7 days a run may take \(sim.sizing.MAX_RUN_SECONDS\); " + SHRINK,
        ),
        (
            ["--duration", "6000", "--save", "REC", "--max-memory", "300M"],
            r"the run needs about [\d.]+ MiB of memory \(12,000 frames of 18 agents held in "
            r"memory\), more than the limit --max-memory 300 MiB; " + SHRINK + r", record nothing "
            r"\(no --save, --connect, --serve\) to stream the frames to --out in bounded memory, "
            r"or change the limit with --max-memory SIZE \(e.g. 64G\)",
        ),
        (
            ["--max-memory", "8X"],
            r"--max-memory: expected a size such as 8G, 512M or 1.5GiB, got '8X'",
        ),
    ],
    ids=["forever", "forever-recorded", "tiny-dt", "years", "over-the-limit", "bad-limit"],
)
def test_simulate_refuses_what_cannot_fit_before_any_work(
    tmp_path, capsys, machine, no_work, extra, match
):
    out, rrd = tmp_path / "never.parquet", tmp_path / "never.rrd"
    extra = [str(rrd) if e == "REC" else e for e in extra]
    argv = ["simulate", "--scenario", "mingle", "--seed", "1", "--out", str(out), *extra]
    code, peak = traced_peak(lambda: main(argv))
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert re.fullmatch(r"reform-sim simulate: error: " + match + r"\n", err), err
    assert peak < REFUSAL_PEAK_BYTES
    assert not out.exists() and not rrd.exists()


def test_a_long_simulation_streams_to_its_file(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sim.episode, "STREAM_CHUNK_BYTES", 40_000)  # a few frames a row group
    out = tmp_path / "long.parquet"
    argv = ["simulate", "--scenario", "hri-conversation", "--seed", "3", "--out", str(out)]
    assert main([*argv, "--set", "talk_duration=8", "--duration", "30", "--max-memory", "4G"]) == 0
    assert pq.ParquetFile(out).num_row_groups > 2
    expected = simulate_episode(
        "hri-conversation", seed=3, duration=30.0, options={"talk_duration": 8.0}
    )
    assert list(read_parquet(out)) == list(expected.dataset)
    printed = capsys.readouterr()
    assert "60 frames of hri-conversation (seed 3, 30 s at 2 Hz, view truth)" in printed.out
    assert printed.err == ""  # a run this short shows no progress bar

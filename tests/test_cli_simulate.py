"""``reform-sim simulate`` and ``reform-sim scenarios``: files written, read back; bad input."""

from __future__ import annotations

import json
import re

import pytest
from rerun.chunk import RrdReader

import scenarios
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
    texts = []
    entities = set()
    for chunk in RrdReader(rrd).stream():
        entities.add(chunk.entity_path)
        if chunk.entity_path == "/events":
            texts += [t[0] for t in chunk.to_record_batch().column("TextLog:text").to_pylist()]
    assert {
        "/world/people/bodies",
        "/world/robot/bodies",
        "/world/groups/truth/members",
    } <= entities
    assert any(t.startswith("approach:") for t in texts)
    assert any("forms" in t for t in texts) and any("leave:" in t for t in texts)


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
        (["--scenario", "dance"], r"unknown scenario 'dance'; known scenarios: hri-conversation"),
        (["--set", "players=1"], r"word-improv: option players must be within \[2, 7\], got 1"),
        (["--set", "players"], r"--set must be KEY=VALUE, got 'players'"),
        (["--set", "players=many"], r"option players must be an integer, got 'many'"),
        (["--duration", "-5"], r"duration must be a positive number of seconds, got -5.0"),
        (["--dropout", "0.1"], r"sensor options need --view robot, got --dropout"),
        (["--view", "robot"], r'view="robot" needs a robot'),
    ],
)
def test_simulate_bad_input_fails_before_any_work(tmp_path, capsys, extra, match):
    out = tmp_path / "never.parquet"
    argv = ["simulate", "--scenario", "word-improv", "--seed", "1", "--out", str(out), *extra]
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
    assert main(["calibrate", "--out", str(tmp_path), "--datasets", str(tmp_path)]) == 2
    assert "no salsa/ folder in it" in capsys.readouterr().err
    assert main(["calibrate", "--out", str(tmp_path), "--seeds", "0"]) == 2
    assert "--seeds must be >= 1, got 0" in capsys.readouterr().err

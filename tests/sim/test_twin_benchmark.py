"""reform-sim benchmark --twin: each detector's F1 predicted at a place, with an interval."""

from __future__ import annotations

import dataclasses
import json

import pytest

from sim.twins import fit_twin, write_twin
from tests.cli_errors import cli_error, run_cli
from tests.sim.test_twin import _frames


@pytest.fixture(scope="module")
def twin_file(tmp_path_factory):
    twin = dataclasses.replace(fit_twin(_frames(people=9), name="place"), episodes=3)
    return write_twin(twin, tmp_path_factory.mktemp("twin") / "twin.json")


def test_benchmark_twin_predicts_each_detector_with_an_interval(twin_file, tmp_path, capsys):
    argv = ["benchmark", "--twin", twin_file, "--detector", "gcff", "--detector", "proximity",
            "--detector", "majority", "--out", tmp_path / "b", "-q"]  # fmt: skip
    status, out, err = run_cli(argv, capsys)
    assert status == 0, err
    data = json.loads((tmp_path / "b" / "benchmark-twin.json").read_text())
    rows = {p["detector"]: p for p in data["predictions"]}
    assert set(rows) == {"gcff", "proximity", "majority"}
    for row in rows.values():
        assert 0.0 <= row["low"] <= row["f1"] <= row["high"] <= 1.0
    assert rows["gcff"]["f1"] > rows["majority"]["f1"]  # a detector beats "everyone alone"
    assert "| gcff |" in out


def test_benchmark_twin_is_deterministic(twin_file, tmp_path, capsys):
    texts = []
    for name in ("a", "b"):
        argv = ["benchmark", "--twin", twin_file, "--detector", "proximity", "--out",
                tmp_path / name, "-q"]  # fmt: skip
        assert run_cli(argv, capsys)[0] == 0
        texts.append((tmp_path / name / "benchmark-twin.json").read_text())
    assert texts[0] == texts[1]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--data", "salsa"], "--twin predicts for the twin's place; it takes no --data"),
        (["--detector", "nobody"], "--detector nobody: expected a catalogued detector"),
    ],
    ids=["data", "unknown-detector"],
)
def test_benchmark_twin_refuses_in_one_line(twin_file, tmp_path, capsys, extra, message):
    line = cli_error(["benchmark", "--twin", twin_file, "--out", tmp_path / "b", *extra], capsys)
    assert message in line

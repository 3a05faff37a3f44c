"""reform-sim tune --twin: a detector's settings chosen on a twin's data, in a file others read."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from reform.detectors import Option, detector_info
from reform.persistence import load_model
from reform.settings import read_settings
from sim.twins import write_twin
from sim.twins.tune import (
    TIE_F1,
    _leaning,
    crowd_limit,
)
from tests.cli_errors import cli_error, run_cli
from tests.sim.test_twin import _frames


@pytest.fixture(scope="module")
def twin_file(place_twin, tmp_path_factory):
    twin = dataclasses.replace(place_twin, episodes=2)  # a small twin: two episodes of 30 s
    return write_twin(twin, tmp_path_factory.mktemp("twin") / "twin.json")


def test_tune_gcff_writes_the_cheapest_group_among_the_best_settings_of_its_grid(
    twin_file, capsys
):
    status, out, err = run_cli(
        ["tune", "--twin", twin_file, "--detector", "gcff", "--jobs", 1, "-q"], capsys
    )
    assert status == 0, err
    path = twin_file.parent / "tuned-gcff.json"
    data = json.loads(path.read_text())
    assert len(data["grid"]) == 49  # stride x mdl, as the catalogue declares them
    best = max(g["f1"] for g in data["grid"])
    near = [g for g in data["grid"] if g["f1"] >= best - TIE_F1]
    cheapest = min(g["options"]["mdl"] for g in near)
    chosen = max((g for g in near if g["options"]["mdl"] == cheapest), key=lambda g: g["f1"])
    assert data["options"] == chosen["options"]
    assert "lowest mdl" in data["chosen_on"]["rule"]
    settings = read_settings(path)
    assert settings.detector == "gcff" and set(settings.options) == {"stride", "mdl"}
    assert settings.about["chosen_on"]["labels read"] == "none"
    assert f"--detector gcff --settings {path}" in out


def test_the_settings_scored_on_two_processes_give_the_same_file(twin_file, tmp_path, capsys):
    written = []
    for jobs in (1, 2):
        out = tmp_path / f"jobs-{jobs}.json"
        argv = ["tune", "--twin", twin_file, "--detector", "gcff", "--jobs", jobs, "--out", out]
        status, _, err = run_cli([*argv, "-q"], capsys)
        assert status == 0, err
        written.append(out.read_bytes())
    assert written[0] == written[1]


def test_tune_reform_trains_on_the_twin_and_writes_a_model(twin_file, tmp_path, capsys):
    out = tmp_path / "m.skops"
    argv = ["tune", "--twin", twin_file, "--detector", "reform", "--out", out, "--jobs", 1, "-q"]
    status, _, err = run_cli(argv, capsys)
    assert status == 0, err
    model = load_model(out)
    assert model.training_summary_["frames"] > 0


@pytest.mark.parametrize(
    ("detector", "message"),
    [
        ("gcff-own", "it reads the settings its dataset ships, which a twin has none of; tune"),
        ("nobody", "--detector: expected a catalogued detector"),
        ("majority", "it has no setting to choose; tune a detector whose options a twin searches"),
        ("dante", "it runs from a model file trained for it, which a twin does not make"),
        ("hysteresis", "it fits itself on training frames; tune reform (the same method) instead"),
    ],
)
def test_tune_refuses_what_it_cannot_tune_in_one_line(twin_file, capsys, detector, message):
    out = twin_file.parent / f"refused-{detector}.json"
    argv = ["tune", "--twin", twin_file, "--detector", detector, "--out", out]
    assert message in cli_error(argv, capsys)
    assert not out.exists()  # refused before any work


def test_detect_takes_the_settings_file_as_it_is(twin_file, tmp_path, capsys):
    from reform.datasets import write_parquet
    from reform.frame import Dataset

    settings = twin_file.parent / "tuned-gcff.json"
    if not settings.exists():
        assert (
            run_cli(["tune", "--twin", twin_file, "--detector", "gcff", "--jobs", 1, "-q"], capsys)[
                0
            ]
            == 0
        )
    data = tmp_path / "place.parquet"
    write_parquet(Dataset(tuple(_frames()), name="place"), data)
    argv = ["detect", "--detector", "gcff", "--settings", settings, "--data", data,
            "--out", tmp_path / "groups.json"]  # fmt: skip
    status, _, err = run_cli(argv, capsys)
    assert status == 0, err
    assert json.loads((tmp_path / "groups.json").read_text())


@pytest.mark.parametrize(
    ("scores", "chosen"),
    [
        # (stride, mdl) scores: the cheapest group within TIE_F1 of the best, then its best
        ({(0.7, 3.0): 0.90, (0.6, 1.0): 0.885, (0.5, 1.0): 0.889, (0.4, 0.5): 0.85}, (0.5, 1.0)),
        ({(0.7, 3.0): 0.90, (0.6, 1.0): 0.87}, (0.7, 3.0)),  # nothing cheaper near the best
        ({(0.7, 3.0): 0.90, (0.5, 3.0): 0.90}, (0.5, 3.0)),  # a tie: the first in grid order
    ],
)
def test_among_settings_a_twin_cannot_tell_apart_the_cheapest_group_is_kept(scores, chosen):
    grid = [dict(stride=s, mdl=m) for s, m in sorted(scores)]
    index = _leaning("gcff", grid, [scores[(g["stride"], g["mdl"])] for g in grid])
    assert (grid[index]["stride"], grid[index]["mdl"]) == chosen


def test_a_detector_whose_options_do_not_lean_keeps_the_best():
    assert _leaning("proximity", [{"distance": 1.0}, {"distance": 1.5}], [0.8, 0.79]) is None
    assert [o.lean for o in detector_info("gcff").options if o.grid] == ["", "low"]
    with pytest.raises(ValueError, match=r"option 'x': lean must be one of"):
        Option("x", "float", 1.0, "x", lean="sideways")


@pytest.mark.parametrize(("people", "frames"), [(6, 244), (100, 244), (240, 125), (1000, 60)])
def test_a_crowd_is_scored_on_fewer_frames_a_party_on_all_it_may(people, frames):
    crowd = [
        f.replace(
            ids=np.arange(1, people + 1),
            position=np.column_stack([np.arange(people), np.zeros(people)]),
            yaw=np.zeros(people),
            kinds=None,
            groups=None,
        )
        for f in _frames()
    ]
    assert crowd_limit(crowd, 244) == frames  # 30,000 people a setting, at least 60 frames


@pytest.mark.parametrize(
    ("detector", "out", "suffix"),
    [("gcff", "x.skops", ".json"), ("reform", "r.json", ".skops")],
    ids=["gcff", "reform"],
)
def test_tune_refuses_an_out_of_another_format_before_any_work(
    twin_file, detector, out, suffix, tmp_path, capsys
):
    path = tmp_path / out
    err = cli_error(["tune", "--twin", twin_file, "--detector", detector, "--out", path], capsys)
    assert err == (
        f"reform-sim tune: error: --out {path}: expected a file name ending in {suffix} (the "
        f"format written), found {Path(out).suffix}"
    )
    assert not path.exists()


def test_a_twin_data_folder_holding_something_else_is_named_by_its_flag(
    twin_file, tmp_path, capsys
):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    out = tmp_path / "tuned.json"
    argv = ["tune", "--twin", twin_file, "--detector", "gcff", "--twin-data", foreign]
    err = cli_error([*argv, "--out", out], capsys)
    assert err.startswith(
        f"reform-sim tune: error: --twin-data {foreign} holds files but no dataset card"
    )
    assert [p.name for p in foreign.iterdir()] == ["notes.txt"] and not out.exists()

"""reform-sim tune --twin: a detector's settings chosen on a twin's data, in a file others read."""

from __future__ import annotations

import dataclasses
import json

import pytest

from reform.persistence import load_model
from sim.twins import fit_twin, write_twin
from sim.twins.tune import SettingsError, read_settings
from tests.cli_errors import cli_error, run_cli
from tests.sim.test_twin import _frames


@pytest.fixture(scope="module")
def twin_file(tmp_path_factory):
    twin = fit_twin(_frames(scale=1.5), name="place")
    twin = dataclasses.replace(twin, episodes=2)  # a small twin: two episodes of 30 s
    return write_twin(twin, tmp_path_factory.mktemp("twin") / "twin.json")


def test_tune_gcff_writes_the_best_setting_of_its_grid(twin_file, capsys):
    status, out, err = run_cli(["tune", "--twin", twin_file, "--detector", "gcff", "-q"], capsys)
    assert status == 0, err
    path = twin_file.parent / "tuned-gcff.json"
    data = json.loads(path.read_text())
    assert len(data["grid"]) == 49  # stride x mdl, as the catalogue declares them
    best = max(data["grid"], key=lambda g: g["f1"])
    assert data["options"] == best["options"]
    name, options = read_settings(path)
    assert name == "gcff" and set(options) == {"stride", "mdl"}
    assert f"--stride {options['stride']:g}" in out.replace(".0 ", " ")


def test_tune_reform_trains_on_the_twin_and_writes_a_model(twin_file, tmp_path, capsys):
    out = tmp_path / "m.skops"
    argv = ["tune", "--twin", twin_file, "--detector", "reform", "--out", out, "-q"]
    status, _, err = run_cli(argv, capsys)
    assert status == 0, err
    model = load_model(out)
    assert model.training_summary_["frames"] > 0


@pytest.mark.parametrize(
    ("detector", "message"),
    [
        ("gcff-own", "it reads the settings its dataset ships"),
        ("nobody", "--detector: expected a catalogued detector"),
    ],
)
def test_tune_refuses_what_it_cannot_tune_in_one_line(twin_file, capsys, detector, message):
    assert message in cli_error(["tune", "--twin", twin_file, "--detector", detector], capsys)


def test_a_settings_file_edited_into_nonsense_is_one_line(tmp_path):
    path = tmp_path / "s.json"
    path.write_text(json.dumps({"format": "reform-sim detector settings", "version": 1,
                                "detector": "gcff", "options": {"stride": -3}}))  # fmt: skip
    with pytest.raises(SettingsError, match=r"s\.json: field options\.stride: .*stride"):
        read_settings(path)
    path.write_text(json.dumps({"format": "reform-sim detector settings", "version": 2}))
    with pytest.raises(SettingsError, match=r"field version: expected 1, found 2"):
        read_settings(path)

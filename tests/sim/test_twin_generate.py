"""reform-sim generate --twin: the twin's place as a labelled synthetic dataset."""

from __future__ import annotations

import dataclasses
import json

import pytest

import scenarios
from reform.datasets import read_parquet
from sim.generate import episode_seed
from sim.twins import read_twin, write_twin
from sim.twins.data import twin_options
from tests.cli_errors import cli_error, run_cli
from tests.sim.test_twin import _frames


@pytest.fixture(scope="module")
def twin_file(place_twin, tmp_path_factory):
    return write_twin(place_twin, tmp_path_factory.mktemp("twin") / "twin.json")


def test_generate_twin_writes_the_twins_place(twin_file, tmp_path, capsys):
    out = tmp_path / "data"
    status, _, err = run_cli(["generate", "--twin", twin_file, "--episodes", 2, "--out", out,
                              "--jobs", 1, "-q"], capsys)  # fmt: skip
    assert status == 0, err
    twin = json.loads(twin_file.read_text())
    card = json.loads((out / "dataset.json").read_text())
    assert card["parameters"]["scenario"] == twin["scenario"]
    assert card["parameters"]["annotation"]["scale"] == twin["annotation"]["scale"]
    assert card["parameters"]["options"]["people"] == 6
    data = read_parquet(out)
    assert len(data) == 2 * round(twin["options"]["duration"] * twin["rate_hz"])
    assert all(f.annotated and f.n_people == 6 for f in data)


def test_generate_twin_is_deterministic(twin_file, tmp_path, capsys):
    for name in ("a", "b"):
        argv = ["generate", "--twin", twin_file, "--episodes", 1, "--out", tmp_path / name, "-q"]
        assert run_cli(argv + ["--jobs", 1], capsys)[0] == 0
    shard = "data/scenario=mingle/episode=0/part.parquet"
    assert (tmp_path / "a" / shard).read_bytes() == (tmp_path / "b" / shard).read_bytes()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--scenario", "mingle"], "--twin fixes the scenario, its options, annotation and rate; "
                                   "got --scenario"),
        (["--set", "people=4"], "got --set"),
    ],
    ids=["scenario", "set"],
)  # fmt: skip
def test_generate_twin_refuses_what_the_twin_fixes(twin_file, tmp_path, capsys, extra, message):
    line = cli_error(["generate", "--twin", twin_file, "--out", tmp_path / "d", *extra], capsys)
    assert line.endswith(message)


def test_generate_needs_a_scenario_or_a_twin(tmp_path, capsys):
    line = cli_error(["generate", "--episodes", 1, "--out", tmp_path / "d"], capsys)
    assert line.endswith("--scenario is required (or give --twin TWIN.json)")


def test_generate_refuses_a_nonsense_twin_in_one_line(twin_file, tmp_path, capsys):
    data = json.loads(twin_file.read_text())
    data["version"] = 7
    bad = tmp_path / "twin.json"
    bad.write_text(json.dumps(data))
    line = cli_error(["generate", "--twin", bad, "--out", tmp_path / "d"], capsys)
    assert f"{bad}: field version: expected 1" in line
    assert not (tmp_path / "d").exists()


def test_generate_refuses_a_twin_rate_off_the_control_steps_naming_its_field(
    twin_file, tmp_path, capsys
):
    data = json.loads(twin_file.read_text())
    data["rate_hz"] = 3
    bad = tmp_path / "twin.json"
    bad.write_text(json.dumps(data))
    line = cli_error(["generate", "--twin", bad, "--out", tmp_path / "d"], capsys)
    assert line.endswith(
        f"{bad}: field rate_hz: expected a rate whose period is a whole number of 0.01 s control "
        "steps (e.g. 1, 2, 4, 5, 10), found 3"
    )
    assert not (tmp_path / "d").exists()


def test_the_annotations_fixed_scale_multiplies_every_position_and_stays_off_old_cards():
    import numpy as np

    from reform.annotation import AnnotationModel

    frames = _frames(n_frames=3)
    out = AnnotationModel(scale=2.0).apply(frames, np.random.default_rng(0))
    assert np.array_equal(out[1].position, 2.0 * frames[1].position)  # exactly, no draw
    assert "scale" not in AnnotationModel(directions=4).to_json()  # cards of before keep bytes
    assert AnnotationModel(scale=0.5).to_json()["scale"] == 0.5
    with pytest.raises(ValueError, match=r"annotation scale must be a finite number > 0 .*, got 0"):
        AnnotationModel(scale=0)


def test_another_seed_grows_the_twins_room_until_its_parties_fit(twin_file, tmp_path, capsys):
    twin = read_twin(twin_file)
    crowded = {"people": 12, "room_side": 4.0, "duration": 10.0}
    tight = dataclasses.replace(twin, options={**twin.options, **crowded})
    assert twin_options(tight) == (dict(tight.options), "")  # its own seed: as fitted
    grown, said = twin_options(tight, seed=tight.seed + 1, episodes=2)
    assert grown["room_side"] > 4.0
    assert said.startswith(f"the twin's room grew from 4 m to {grown['room_side']:g} m")
    for k in range(2):  # every party of that seed fits the grown room
        scenarios.make(tight.scenario, seed=episode_seed(tight.seed + 1, k), **grown)

    path = write_twin(tight, tmp_path / "tight.json")
    argv = ["generate", "--twin", path, "--seed", tight.seed + 1, "--episodes", 2,
            "--out", tmp_path / "d", "--jobs", 1, "-q"]  # fmt: skip
    status, _, err = run_cli(argv, capsys)
    assert status == 0, err
    assert f"{path}: {said}" in err.splitlines()
    card = json.loads((tmp_path / "d" / "dataset.json").read_text())
    assert card["parameters"]["options"]["room_side"] == grown["room_side"]

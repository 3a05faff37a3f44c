"""reform-sim benchmark --twin: each detector's F1 predicted at a place, with an interval."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from reform import Dataset
from reform.datasets import write_parquet
from sim.cli.benchmark_twin import UNCALIBRATED
from sim.twins import fit_twin, read_twin, twin_data, write_twin
from sim.twins.predict import Candidate, predict
from tests.cli_errors import cli_error, run_cli
from tests.sim.test_twin import _frames


def _fitted(made_once, seed: int):
    """The twin of ``_frames(people=9)`` with ``seed``, fitted once for every worker."""
    return read_twin(
        made_once(
            f"nine-people-twin-{seed}.json",
            lambda path: write_twin(fit_twin(_frames(people=9), name="place", seed=seed), path),
        )
    )


@pytest.fixture(scope="module")
def twin_file(tmp_path_factory, made_once):
    # in a folder of this module's own: benchmark --twin generates its data beside it
    twin = dataclasses.replace(_fitted(made_once, 0), episodes=3)
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
        (["--data", "a", "--data", "b"],
         "--data with --twin: expected the place's one recording, found 2"),  # fmt: skip
        (["--data", "nowhere"], "nowhere: no such file or folder, nor a dataset name"),
        (["--detector", "nobody"], "--detector nobody: expected a catalogued detector"),
        (["--temporal"], "--temporal: not read with --twin (it sets how labelled datasets"),
        (["--max-memory", "1G"], "--max-memory: not read with --twin"),
        (["--frames", "test"], "--frames: not read with --twin"),
    ],
    ids=["two-recordings", "no-recording", "unknown-detector", "temporal", "memory", "frames"],
)
def test_benchmark_twin_refuses_in_one_line(twin_file, tmp_path, capsys, extra, message):
    line = cli_error(["benchmark", "--twin", twin_file, "--out", tmp_path / "b", *extra], capsys)
    assert message in line
    assert not (tmp_path / "b").exists()


def test_the_places_recording_calibrates_the_predictions_without_its_groups(
    twin_file, tmp_path, capsys
):
    frames = _frames(people=9)
    rng = np.random.default_rng(0)
    shuffled = []
    for f in frames:  # the same frames, each with groups drawn at random
        ids = rng.permutation(f.ids.tolist()).tolist()
        shuffled.append(f.replace(groups=(tuple(ids[:4]), tuple(ids[4:]))))
    runs = {}
    for name, recording in (
        ("labelled", frames),
        ("unlabelled", [f.replace(groups=None) for f in frames]),
        ("shuffled", shuffled),
    ):
        path = write_parquet(Dataset(tuple(recording), name="place"), tmp_path / f"{name}.parquet")
        argv = ["benchmark", "--twin", twin_file, "--data", path, "--detector", "gcff",
                "--detector", "proximity", "--detector", "hvff", "--detector", "majority",
                "--out", tmp_path / name, "-q"]  # fmt: skip
        status, out, err = run_cli(argv, capsys)
        assert status == 0, err
        runs[name] = json.loads((tmp_path / name / "benchmark-twin.json").read_text())
    predictions = runs["labelled"]["predictions"]
    for name in ("unlabelled", "shuffled"):  # the recording's groups are never read
        assert runs[name]["predictions"] == predictions
    argv = ["benchmark", "--twin", twin_file, "--detector", "gcff", "--detector", "proximity",
            "--detector", "hvff", "--detector", "majority", "--out", tmp_path / "twin",
            "-q"]  # fmt: skip
    status, alone, _ = run_cli(argv, capsys)
    assert status == 0
    twin_only = json.loads((tmp_path / "twin" / "benchmark-twin.json").read_text())
    assert twin_only["place"] is None
    # without the recording, the table says how to calibrate it; with it, it does not
    assert alone.endswith(f"\n{UNCALIBRATED}\n") and UNCALIBRATED not in out
    assert UNCALIBRATED in (tmp_path / "twin" / "benchmark-twin.md").read_text()
    # the twin's own scores are those it predicts without the recording
    assert [p["twin_f1"] for p in predictions] == [p["f1"] for p in twin_only["predictions"]]
    for row in predictions:
        assert 0.0 <= row["low"] <= row["f1"] <= row["high"] <= 1.0
        assert 0.0 <= row["agreement_twin"] <= 1.0 and 0.0 <= row["agreement_place"] <= 1.0
    # "everyone alone" scores on the frames without a group: the consensus says which, not the
    # line through the detectors that group people
    majority = next(p for p in predictions if p["detector"] == "majority")
    assert majority["f1"] == majority["agreement_place"]
    assert runs["labelled"]["place"].endswith("labelled.parquet")
    assert "agreement: twin | place" in out and "its recording" in out


def test_a_variant_added_beside_the_catalogue_moves_no_other_prediction(twin_file):
    twin = read_twin(twin_file)
    data = list(twin_data(twin, twin_file.parent / "twin-data"))
    place = [f.replace(groups=None) for f in _frames(people=9)]
    catalogue = [Candidate(n, n) for n in ("gcff", "proximity", "hvff", "majority")]
    variant = Candidate("gcff (0.3 m)", "gcff", {"stride": 0.3}, votes=False)
    alone = predict(data, catalogue, place=place)
    beside = predict(data, [*catalogue, variant], place=place)
    assert [(p.label, p.f1, p.agreement) for p in beside[:-1]] == [
        (p.label, p.f1, p.agreement) for p in alone
    ]
    assert beside[-1].label == "gcff (0.3 m)" and beside[-1].agreement is not None
    # a voter added does move the consensus
    voting = predict(data, [*catalogue, dataclasses.replace(variant, votes=True)], place=place)
    assert [p.agreement for p in voting[:-1]] != [p.agreement for p in alone]


@pytest.fixture(scope="module")
def second_twin(tmp_path_factory, twin_file, made_once):
    """A twin of the same place fitted with another seed, and one of another place."""
    again = dataclasses.replace(_fitted(made_once, 1), episodes=3)
    other = dataclasses.replace(read_twin(twin_file), name="elsewhere")
    return (
        write_twin(again, tmp_path_factory.mktemp("again") / "twin.json"),
        write_twin(other, tmp_path_factory.mktemp("other") / "twin.json"),
    )


def test_twins_of_one_place_predict_their_mean(twin_file, second_twin, tmp_path, capsys):
    again, _ = second_twin
    alone = {}
    for name, twin in (("a", twin_file), ("b", again)):
        argv = ["benchmark", "--twin", twin, "--detector", "gcff", "--detector", "majority",
                "--out", tmp_path / name, "-q"]  # fmt: skip
        assert run_cli(argv, capsys)[0] == 0
        data = json.loads((tmp_path / name / "benchmark-twin.json").read_text())
        alone[name] = {p["detector"]: p for p in data["predictions"]}
    argv = ["benchmark", "--twin", twin_file, "--twin", again, "--detector", "gcff",
            "--detector", "majority", "--out", tmp_path / "both", "-q"]  # fmt: skip
    status, out, err = run_cli(argv, capsys)
    assert status == 0, err
    data = json.loads((tmp_path / "both" / "benchmark-twin.json").read_text())
    assert data["twin"] == [str(twin_file), str(again)]
    for k, run in zip("ab", data["each_twin"], strict=True):  # each twin as it predicts alone
        assert [p["f1"] for p in run] == [alone[k][p["detector"]]["f1"] for p in run]
    for p in data["predictions"]:
        a, b = alone["a"][p["detector"]], alone["b"][p["detector"]]
        assert p["f1"] == pytest.approx((a["f1"] + b["f1"]) / 2)
        assert (p["low"], p["high"]) == (min(a["low"], b["low"]), max(a["high"], b["high"]))
    assert "the mean over 2 venue twins" in out and "each twin: " in out


@pytest.mark.parametrize(
    ("which", "extra", "message"),
    [
        (1, [], "expected twins of one place, found a twin of 'elsewhere' beside one of 'place'"),
        (0, ["--twin-data", "d"], "--twin-data: expected one --twin with it, found 2"),
    ],
    ids=["two-places", "twin-data"],
)
def test_several_twins_refuse_in_one_line(
    twin_file, second_twin, tmp_path, capsys, which, extra, message
):
    argv = ["benchmark", "--twin", twin_file, "--twin", second_twin[which], *extra,
            "--out", tmp_path / "b"]  # fmt: skip
    assert message in cli_error(argv, capsys)
    assert not (tmp_path / "b").exists()


def test_the_same_twin_file_twice_is_refused_in_one_line(twin_file, tmp_path, capsys):
    argv = ["benchmark", "--twin", twin_file, "--twin", twin_file, "--out", tmp_path / "b"]
    assert cli_error(argv, capsys) == (
        f"reform-sim benchmark: error: --twin {twin_file}: twin file {twin_file.resolve()} is "
        f"given twice (also as --twin {twin_file}); give each twin file once"
    )
    assert not (tmp_path / "b").exists()


def test_two_twins_of_one_seed_are_refused_naming_both(twin_file, tmp_path, capsys):
    copy = tmp_path / "copy.json"
    copy.write_bytes(twin_file.read_bytes())
    argv = ["benchmark", "--twin", twin_file, "--twin", copy, "--out", tmp_path / "b"]
    assert cli_error(argv, capsys) == (
        f"reform-sim benchmark: error: --twin {copy}: field seed: expected twins fitted with "
        f"different seeds, found seed 0 in {copy} and in {twin_file}"
    )
    assert not (tmp_path / "b").exists()



def test_a_twin_data_folder_holding_something_else_is_named_by_its_flag(
    twin_file, tmp_path, capsys
):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    argv = ["benchmark", "--twin", twin_file, "--twin-data", foreign, "--out", tmp_path / "b"]
    err = cli_error(argv, capsys)
    assert err.startswith(
        f"reform-sim benchmark: error: --twin-data {foreign} holds files but no dataset card"
    )
    assert [p.name for p in foreign.iterdir()] == ["notes.txt"]


def test_twin_data_without_a_twin_is_refused_in_one_line(tmp_path, capsys):
    argv = ["benchmark", "--twin-data", tmp_path / "d", "--out", tmp_path / "b"]
    assert cli_error(argv, capsys).endswith(
        "--twin-data is the generated data of a --twin; give --twin TWIN.json"
    )
    assert not (tmp_path / "b").exists()

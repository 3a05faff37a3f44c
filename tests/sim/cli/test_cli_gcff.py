"""``reform-sim evaluate|detect --detector gcff|gcff-own|gcff-tuned``: one stated setting, the
dataset's own settings, settings searched on training frames; settings files; options."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from sim.cli import main


def _cell(items) -> np.ndarray:
    array = np.empty((1, len(items)), dtype=object)
    for i, item in enumerate(items):
        array[0, i] = item
    return array


def write_gcff_folder(folder: Path, *, settings: dict | None) -> Path:
    """Two frames in centimetres, each a face-to-face pair (120 cm apart) and a loner."""
    frame = np.array(
        [[1, 0.0, 0.0, 0.0], [2, 120.0, 0.0, math.pi], [3, 600.0, 600.0, 1.0]], dtype=float
    )
    folder.mkdir(parents=True, exist_ok=True)
    scipy.io.savemat(
        folder / "features.mat",
        {"features": _cell([frame, frame + [0, 5, 5, 0]]), "timestamp": np.array([[1.0, 2.0]])},
    )
    groups = _cell([np.array([[1, 2]], dtype=float)])
    scipy.io.savemat(
        folder / "groundtruth.mat",
        {"GTgroups": _cell([groups, groups]), "GTtimestamp": np.array([[1.0, 2.0]])},
    )
    if settings is not None:
        scipy.io.savemat(folder / "settings_gc.mat", settings)
    return folder


def detect(
    tmp_path: Path, *args: str, detector: str = "gcff"
) -> tuple[list[list[list[int]]], dict]:
    out = tmp_path / "detections.json"
    assert main(["detect", "--detector", detector, *args, "--out", str(out)]) == 0
    result = json.loads(out.read_text())
    return [record["groups"] for record in result["frames"]], result


def detect_error(tmp_path: Path, capsys, *args: str, detector: str = "gcff") -> str:
    """``reform-sim detect --detector DETECTOR ARGS`` exits with status 2: its stderr."""
    code = main(["detect", "--detector", detector, *args, "--out", str(tmp_path / "x.json")])
    assert code == 2
    return capsys.readouterr().err


# The pair costs 2 x 100 cm² together; together it saves one label cost (mdl). With mdl =
# 30,000 cm² (gcff's stated setting) it is a group; with mdl = 100 cm² it is not worth it.
PAIR = [[[1, 2]], [[1, 2]]]
NONE = [[], []]


def test_gcff_own_uses_the_folders_settings(tmp_path, capsys):
    folder = write_gcff_folder(tmp_path / "Scene", settings={"stride": 70.0, "mdl": 100.0})
    groups, result = detect(tmp_path, "--data", str(folder), detector="gcff-own")
    assert groups == NONE
    assert result["detector_params"]["settings"] == {"Scene": [0.7, pytest.approx(0.01)]}
    assert "settings_gc.mat (Scene: stride 0.7 m, mdl 0.01 m²)" in capsys.readouterr().err


def test_gcff_is_one_stated_setting_whatever_the_folder_ships(tmp_path):
    folder = write_gcff_folder(tmp_path / "Scene", settings={"stride": 70.0, "mdl": 100.0})
    groups, result = detect(tmp_path, "--data", str(folder))
    assert groups == PAIR
    assert (result["detector_params"]["stride"], result["detector_params"]["mdl"]) == (0.7, 3.0)


@pytest.mark.parametrize(
    "args",
    [["--mdl", "0.01"], ["--option", "mdl=0.01"], ["--option", "mdl=0.01", "--stride", "0.7"]],
    ids=["flag", "option", "both-kinds"],
)
def test_gcff_options_by_flag_or_by_option(tmp_path, args):
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    groups, result = detect(tmp_path, "--data", str(folder), *args)
    assert groups == NONE
    assert result["detector_params"]["mdl"] == pytest.approx(0.01)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--option", "mdl=-1"],
            "detector 'gcff': option mdl expects a float in m² from 1e-06 to 10,000, got a float "
            "(-1.0)",
        ),
        (["--option", "mdl"], "--option expects NAME=VALUE, got 'mdl'"),
        (
            ["--option", "size=3"],
            "detector 'gcff' has no option 'size'; its options: stride, mdl, orientation",
        ),
        (["--mdl", "1", "--option", "mdl=2"], "gcff: give mdl once (--mdl or --option mdl=)"),
    ],
    ids=["out-of-range", "no-equals", "unknown", "twice"],
)
def test_bad_options_are_one_line(tmp_path, capsys, args, message):
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    err = detect_error(tmp_path, capsys, "--data", str(folder), *args)
    assert message in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("settings", [None, {"foo": 1.0}], ids=["no-file", "no-stride-or-mdl"])
def test_gcff_own_without_settings_is_one_line(tmp_path, capsys, settings):
    folder = write_gcff_folder(tmp_path / "Scene", settings=settings)
    err = detect_error(tmp_path, capsys, "--data", str(folder), detector="gcff-own")
    assert "gcff-own: dataset 'Scene': sequence 'Scene' ships no GCFF settings" in err


def test_settings_file_in_centimetres(tmp_path):
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    settings = tmp_path / "settings_gc.mat"
    scipy.io.savemat(settings, {"stride": 70.0, "mdl": 100.0})
    groups, result = detect(tmp_path, "--data", str(folder), "--settings", str(settings))
    assert groups == NONE
    assert result["detector_params"]["mdl"] == pytest.approx(0.01)


def test_settings_file_in_pixels_takes_the_datasets_scale(tmp_path):
    """A pose-estimation set in pixels, its settings in the same pixels: read with
    --metres-per-pixel as the positions are (0.01 m per pixel makes the file's cm-like values
    metres / 100, as centimetres would)."""
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    settings = tmp_path / "settings_gc.mat"
    scipy.io.savemat(settings, {"stride": 70.0, "mdl": 100.0})
    pixels = ["--units", "px", "--metres-per-pixel", "0.01"]
    groups, result = detect(tmp_path, "--data", str(folder), *pixels, "--settings", str(settings))
    assert groups == NONE
    assert result["detector_params"]["stride"] == pytest.approx(0.7)
    assert result["detector_params"]["mdl"] == pytest.approx(0.01)


def test_gcff_tuned_on_training_data(tmp_path, capsys):
    train = write_gcff_folder(tmp_path / "Train", settings=None)
    folder = write_gcff_folder(tmp_path / "Scene", settings={"stride": 70.0, "mdl": 100.0})
    groups, _ = detect(
        tmp_path, "--data", str(folder), "--tune-on", str(train), detector="gcff-tuned"
    )
    assert groups == PAIR
    assert f"gcff-tuned: tuned on 2 frames of {train}" in capsys.readouterr().err


def test_gcff_tuned_without_training_frames_is_one_line(tmp_path, capsys):
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    err = detect_error(tmp_path, capsys, "--data", str(folder), detector="gcff-tuned")
    assert "--detector gcff-tuned learns its settings from annotated training frames" in err


def test_evaluate_writes_scores(tmp_path):
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    out = tmp_path / "evaluation.json"
    assert main(["evaluate", "--detector", "gcff", "--data", str(folder), "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["detector"] == "gcff"
    assert result["2/3"]["f1"] == 1.0


def test_conflicting_sources_are_an_error(tmp_path, capsys):
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    settings = tmp_path / "settings_gc.mat"
    scipy.io.savemat(settings, {"stride": 70.0, "mdl": 100.0})
    err = detect_error(
        tmp_path, capsys, "--data", str(folder), "--stride", "0.6", "--settings", str(settings)
    )
    assert "gcff takes --settings FILE.mat or --stride/--mdl/--option; got both" in err
    err = detect_error(
        tmp_path, capsys, "--data", str(folder), "--stride", "0.6", "--tune-on", str(folder)
    )
    assert "--tune-on is for a detector that learns its settings from training frames" in err


def test_bad_settings_file_is_named(tmp_path, capsys):
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    settings = tmp_path / "broken.mat"
    scipy.io.savemat(settings, {"stride": 70.0})
    err = detect_error(tmp_path, capsys, "--data", str(folder), "--settings", str(settings))
    assert "broken.mat" in err and "expected a variable 'mdl'" in err


def test_a_folder_of_sequences_uses_each_sequences_own_settings(shared_datasets, tmp_path, capsys):
    # coffeebreak/README.md: Seq1 ships 50 cm / 8000 cm², Seq2 20 cm / 7000 cm², and the
    # original GCFF code scores F1 .770 and .944 with them (T = 2/3).
    out = tmp_path / "scores.json"
    argv = ["evaluate", "--data", str(shared_datasets / "coffeebreak"), "--detector", "gcff-own"]
    assert main([*argv, "--json", str(out)]) == 0
    assert (
        "Seq1: stride 0.5 m, mdl 0.8 m²; Seq2: stride 0.2 m, mdl 0.7 m²" in capsys.readouterr().err
    )
    by_sequence = json.loads(out.read_text())["by_sequence"]
    assert round(by_sequence["Seq1"]["2/3"]["f1"], 3) == 0.770
    assert round(by_sequence["Seq2"]["2/3"]["f1"], 3) == 0.944


def test_orientation_by_option_beside_a_settings_file(tmp_path, capsys):
    """An option that is not a setting (the orientation) goes with a settings_gc.mat: GCFF
    follows the heads, which this folder (bodies only) does not have."""
    folder = write_gcff_folder(tmp_path / "Scene", settings=None)
    settings = tmp_path / "settings_gc.mat"
    scipy.io.savemat(settings, {"stride": 70.0, "mdl": 100.0})
    argv = ["--data", str(folder), "--settings", str(settings), "--option", "orientation=head"]
    assert "orientation='head' needs head yaws" in detect_error(tmp_path, capsys, *argv)
    both = ["--data", str(folder), "--gcff-orientation", "body", "--option", "orientation=head"]
    assert "gcff: give orientation once (--gcff-orientation or --option orientation=)" in (
        detect_error(tmp_path, capsys, *both)
    )

"""``reform-sim train``'s choice of frames: ``--every K`` thins them per sequence, ``--validation
F`` holds out the last of them to stop DANTE early; each refused in one line where it means
nothing."""

from __future__ import annotations

import pytest
from cli_errors import cli_error
from toy_scenes import toy_frames

from reform import Dataset, write_parquet
from reform.dante import load_dante
from sim.cli import main


@pytest.fixture
def toy_dataset(tmp_path):
    frames = [f.replace(sequence=s) for s in ("a", "b") for f in toy_frames(0, 20)]
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(frames), name="toy", source="toy_scenes"), path)
    return path


def test_every_keeps_every_kth_frame_of_each_sequence(toy_dataset, tmp_path, capsys):
    argv = ["train", "--data", toy_dataset, "--classifier", "logistic-regression"]
    assert main([str(a) for a in [*argv, "--every", "3", "--out", tmp_path / "m.skops"]]) == 0
    assert "on 14 frames of toy" in capsys.readouterr().out  # 7 of each sequence's 20


def test_dante_stops_on_the_validation_frames(toy_dataset, tmp_path, capsys):
    pytest.importorskip("torch")
    out = tmp_path / "d.safetensors"
    argv = ["train", "--detector", "dante", "--data", toy_dataset, "--every", "2"]
    argv += ["--validation", "0.25", "--option", "epochs=3", "--option", "patience=1"]
    argv += ["--option", "batch_size=64", "--out", out]
    assert main([str(a) for a in argv]) == 0
    captured = capsys.readouterr()
    # 15 training frames of each sequence thinned to 8, 5 validation frames thinned to 3
    assert "training DANTE on 16 frames of toy (at most 3 epochs, stopping on 6 validation" in (
        captured.err
    )
    assert "validation loss" in captured.err
    assert load_dante(out).training_summary_["validation_frames"] == 6


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--every", "0"], "--every keeps every K-th frame: K must be 1 or more, got 0"),
        (
            ["--validation", "1.5"],
            "--validation is the share of training frames held out: in (0, 1), got 1.5",
        ),
        (
            ["--validation", "0.2"],
            "--validation stops DANTE's training early; REFORM's classifiers train once "
            "(--tune cross-validates them)",
        ),
        (
            ["--detector", "dante", "--option", "patience=3"],
            "--option patience= stops training early on --validation F frames",
        ),
    ],
)
def test_frame_choices_that_mean_nothing_are_refused(extra, message, toy_dataset, tmp_path, capsys):
    out = tmp_path / ("m.safetensors" if "dante" in extra else "m.skops")
    argv = ["train", "--data", toy_dataset, *extra, "--out", out]
    assert cli_error(argv, capsys) == f"reform-sim train: error: {message}"
    assert not out.exists()

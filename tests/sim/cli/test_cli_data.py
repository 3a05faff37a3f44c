"""``reform-sim data info`` and ``reform-sim data convert``."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.io

from reform import Dataset, Frame
from reform.datasets import load_salsa, read_parquet, write_parquet
from sim.cli import main


def _info_says(data, lines, capsys, *options) -> None:
    """``reform-sim data info --data DATA OPTIONS`` exits 0 and prints each of ``lines``."""
    assert main(["data", "info", "--data", str(data), *options]) == 0
    out = capsys.readouterr().out
    missing = [line for line in lines if line not in out]
    assert not missing, out


def test_info_salsa(salsa_dir, capsys):
    lines = [
        "dataset          salsa (format salsa)",
        "frames           1145",
        "annotated frames 1143",
        "units            m",
        "18 distinct ids",
        "session1: 645 frames, 644 annotated",
        "session2: 500 frames, 499 annotated",
        # The canonical group-size table of the SALSA README.
        "  size      1    2    3    4    5    6    7    8   12",
        "  groups 1684 1554 1705  952  539  381  238   25    1",
        "F-formations     5395",
        "missing_from_groundtruth: 129",
        "duplicate_singletons: 3",
    ]
    _info_says(salsa_dir, lines, capsys)


def test_info_babble_json(babble_dir, capsys):
    assert main(["data", "info", "--data", str(babble_dir), "--format", "babble", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["format"] == "babble"
    assert summary["frames"] == 3481
    assert summary["annotated_frames"] == 99
    assert summary["group_sizes"] == {"1": 29, "2": 8, "3": 18, "4": 10, "5": 20, "6": 15, "7": 23}
    assert summary["report"]["heads_swapped_back"] == 107
    assert summary["report"]["torso_from_head"] == [[79, 6], [520, 4], [721, 3]]


def _gcff_folder(folder):
    folder.mkdir()
    features = np.empty((1, 2), dtype=object)
    features[0, 0] = np.array([[1, 0.0, 0.0, 0.0], [2, 70.0, 0.0, np.pi]])
    features[0, 1] = np.array([[1, 0.0, 0.0, 0.0]])
    groups = np.empty((1, 1), dtype=object)
    inner = np.empty((1, 1), dtype=object)
    inner[0, 0] = np.array([[1.0, 2.0]])
    groups[0, 0] = inner
    scipy.io.savemat(
        folder / "features.mat", {"features": features, "timestamp": np.array([[1.0, 2.0]])}
    )
    scipy.io.savemat(
        folder / "groundtruth.mat", {"GTgroups": groups, "GTtimestamp": np.array([[1.0]])}
    )
    scipy.io.savemat(folder / "settings_gc.mat", {"stride": 70.0, "mdl": 30000.0})
    return folder


def test_info_gcff_units(tmp_path, capsys):
    folder = _gcff_folder(tmp_path / "tiny")
    lines = [
        "units            m (file in cm, converted)",
        "frames           2",
        "annotated frames 1",
        '"stride_m": 0.7',
    ]
    _info_says(folder, lines, capsys)
    assert main(["data", "info", "--data", str(folder), "--units", "m", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["group_sizes"] == {"2": 1}


def test_convert_then_info(tmp_path, salsa_dir, capsys):
    out = tmp_path / "salsa.parquet"
    assert main(["data", "convert", "--data", str(salsa_dir), "--out", str(out)]) == 0
    assert read_parquet(out).frames == load_salsa(salsa_dir).frames
    capsys.readouterr()
    _info_says(out, ["(format parquet)", "frames           1145"], capsys)


def test_info_parquet_with_robot_and_empty_frame(tmp_path, capsys):
    frames = (
        Frame(
            ids=[1, 2],
            kinds=("human", "robot"),
            position=[[0, 0], [1, 0]],
            yaw=[0, 3],
            groups=((1, 2),),
        ),
        Frame(ids=[], position=np.zeros((0, 2)), yaw=[], time=1.0),
    )
    path = write_parquet(Dataset(frames=frames, name="tiny"), tmp_path / "tiny.parquet")
    _info_says(path, ["robots           in 1 frames", "per frame min 0, median 1, max 2"], capsys)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["data", "info", "--data", "/nonexistent/place"],
            "no such file or folder, nor a dataset name",
        ),
        (
            ["data", "info", "--data", "{babble}", "--units", "cm"],
            "babble format stores positions in 'm'",
        ),
        (["data", "info", "--data", "{tmp}"], "expected a dataset in one of the formats: salsa"),
        (
            ["data", "info", "--data", "{salsa}", "--format", "gcff"],
            "salsa: expected a GCFF folder (features.mat, groundtruth.mat) or a folder of them",
        ),
    ],
    ids=["missing-path", "units-contradict-format", "unknown-format", "wrong-format"],
)
def test_errors_are_one_line(argv, message, salsa_dir, babble_dir, tmp_path, capsys):
    argv = [a.format(salsa=salsa_dir, babble=babble_dir, tmp=tmp_path) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("reform-sim data: error: ")
    assert message in err
    assert err.count("\n") == 1


def test_help(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["data", "info", "--help"])
    assert exit_info.value.code == 0
    assert "group-size" in capsys.readouterr().out


def test_an_unfinished_generate_folder_needs_allow_incomplete(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["generate", "--scenario", "hri-passing", "--episodes", "2", "--seed", "0"]
    assert main([*argv, "--duration", "5", "--quiet", "--out", str(out)]) == 0
    card = out / "dataset.json"
    data = json.loads(card.read_text())
    data["complete"] = False  # as a run stopped before its last episode leaves it
    card.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["data", "info", "--data", str(out)]) == 2
    err = capsys.readouterr().err
    assert "incomplete dataset (2 of 2 episodes written)" in err and "--allow-incomplete" in err
    assert main(["data", "info", "--data", str(out), "--allow-incomplete"]) == 0
    assert "frames" in capsys.readouterr().out


def _gcff_with_absent_member(folder):
    folder.mkdir(parents=True)
    features = np.empty((1, 1), dtype=object)
    features[0, 0] = np.array([[1, 0.0, 0.0, 0.0], [2, 100.0, 0.0, 3.1], [3, np.nan, 0, 0]])
    groups = np.empty((1, 1), dtype=object)
    members = np.empty((1, 1), dtype=object)
    members[0, 0] = np.array([[1.0, 2.0, 42.0]])
    groups[0, 0] = members
    scipy.io.savemat(folder / "features.mat", {"features": features, "timestamp": [[1.0]]})
    scipy.io.savemat(folder / "groundtruth.mat", {"GTgroups": groups, "GTtimestamp": [[1.0]]})
    return folder


def test_info_counts_the_repairs_and_strict_refuses(tmp_path, capsys):
    folder = _gcff_with_absent_member(tmp_path / "quirks")
    assert main(["data", "info", "--data", str(folder), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)["report"]
    assert report["repairs"] == {"people_dropped_nan": 1, "groundtruth_members_absent": 1}
    assert main(["data", "info", "--data", str(folder), "--strict"]) == 2
    err = capsys.readouterr().err
    assert "frame 1, row 3 (ID 3): field 'x'" in err and "refused by --strict" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--units", "px"], "--units px needs --metres-per-pixel M"),
        (["--metres-per-pixel", "0.01"], "--metres-per-pixel is the scale of --units px"),
    ],
    ids=["pixels-without-scale", "scale-without-pixels"],
)
def test_pixel_units_need_their_scale(tmp_path, capsys, argv, message):
    folder = _gcff_with_absent_member(tmp_path / "px")
    assert main(["data", "info", "--data", str(folder), *argv]) == 2
    assert message in capsys.readouterr().err
    assert (
        main(["data", "info", "--data", str(folder), "--units", "px", "--metres-per-pixel", "0.01"])
        == 0
    )

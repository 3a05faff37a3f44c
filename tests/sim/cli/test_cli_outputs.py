"""Every output option of ``reform-sim`` is checked before the command's work starts: an existing
folder where a file is written, a path under a file, a folder that cannot be created, each one
line naming the option, the path, what was expected and what was found (exit status 2)."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_errors import cli_error
from toy_scenes import toy_frames

from reform import Dataset, write_parquet
from sim.cli import main


@pytest.fixture
def toy_dataset(tmp_path):
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 20)), name="toy", source="toy_scenes"), path)
    return path


@pytest.fixture
def places(tmp_path):
    """An existing folder ``folder`` (holding ``folder.parquet/``) and a file ``afile``."""
    (tmp_path / "folder").mkdir()
    (tmp_path / "folder.parquet").mkdir()
    (tmp_path / "rep.md").mkdir()
    (tmp_path / "afile").write_text("not a folder")
    (tmp_path / "datasets" / "salsa").mkdir(parents=True)
    (tmp_path / "datasets" / "babble").mkdir()
    return tmp_path


def _tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


DATA = "{data}"  # replaced by the toy dataset

FOLDER_AS_FILE = [
    (["detect", "--detector", "majority", "--data", DATA, "--out"], "--out", "folder"),
    (["data", "convert", "--data", DATA, "--out"], "--out", "folder"),
    (["train", "--data", DATA, "--out"], "--out", "folder"),
    (["simulate", "--scenario", "mingle", "--seed", "0", "--out"], "--out", "folder.parquet"),
    (["policy", "evaluate", "--env", "ReformSim/Mingle-v0", "--out"], "--out", "folder"),
]


@pytest.mark.parametrize(("argv", "option", "name"), FOLDER_AS_FILE)
def test_an_existing_folder_given_for_a_file(argv, option, name, places, toy_dataset, capsys):
    before = _tree(places)
    argv = [toy_dataset if a == DATA else a for a in argv]
    err = cli_error([*argv, places / name], capsys)
    command = argv[0]
    assert err == (
        f"reform-sim {command}: error: {option} {places / name}: "
        "expected a file path, found an existing folder"
    )
    assert _tree(places) == before


@pytest.mark.parametrize(
    ("argv", "name"),
    [
        (["evaluate", "--detector", "majority", "--data", DATA], "evaluation.json"),
        (["characterize", "--data", DATA], "characterisation.md"),
    ],
)
def test_a_report_file_that_is_a_folder(argv, name, places, toy_dataset, capsys):
    (places / "reports" / name).mkdir(parents=True)
    before = _tree(places)
    argv = [toy_dataset if a == DATA else a for a in argv]
    err = cli_error([*argv, "--out", places / "reports"], capsys)
    assert err == (
        f"reform-sim {argv[0]}: error: --out {places / 'reports' / name}: "
        "expected a file path, found an existing folder"
    )
    assert _tree(places) == before


UNDER_A_FILE = [
    (["evaluate", "--detector", "majority", "--data", DATA, "--out"], "--out", "sub"),
    (["evaluate", "--detector", "majority", "--data", DATA, "--save"], "--save", "x.rrd"),
    (
        ["detect", "--detector", "majority", "--data", DATA, "--out", "{tmp}/d.json", "--save"],
        "--save",
        "x.rrd",
    ),
    (["simulate", "--scenario", "mingle", "--seed", "0", "--out"], "--out", "s.parquet"),
    (
        ["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "0", "--out"],
        "--out",
        "sub",
    ),
    (["stress", "--grid", "small", "--out"], "--out", "sub"),
    (["demo", "--quick", "--out"], "--out", "sub"),
    (["experiment", "paper", "--data", "salsa=s", "--data", "babble=b", "--out"], "--out", "r"),
    (["experiment", "gcff", "--data", "salsa=s", "--data", "babble=b", "--out"], "--out", "r"),
    (["experiment", "hri", "--recordings", "--out"], "--out", "h"),
    (["experiment", "sim2real", "--data", "salsa=s", "--data", "babble=b", "--out"], "--out", "r"),
    (
        [
            "experiment",
            "sim2real",
            "--data",
            "salsa=s",
            "--data",
            "babble=b",
            "--out",
            "{tmp}/x",
            "--synthetic",
        ],
        "--synthetic",
        "syn",
    ),
    (["calibrate", "--data", "{tmp}/datasets", "--out"], "--out", "sub"),
]


@pytest.mark.parametrize(("argv", "option", "below"), UNDER_A_FILE)
def test_a_path_under_a_file(argv, option, below, places, toy_dataset, capsys):
    before = _tree(places)
    argv = [toy_dataset if a == DATA else a.replace("{tmp}", str(places)) for a in argv]
    path = places / "afile" / below
    err = cli_error([*argv, path], capsys)
    command = argv[0]
    assert err.startswith(f"reform-sim {command}: error: {option} {path}: "), err
    assert err.endswith(f"expected a folder at {places / 'afile'}, found a file"), err
    assert _tree(places) == before


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["stress", "--grid", "small", "--out"], "--out"),
        (["demo", "--quick", "--out"], "--out"),
        (["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "0", "--out"], "--out"),
        (["calibrate", "--data", "{tmp}/datasets", "--out"], "--out"),
        (["experiment", "hri", "--recordings", "--out"], "--out"),
        (["evaluate", "--detector", "majority", "--data", "{tmp}/toy.parquet", "--out"], "--out"),
    ],
)
def test_a_file_given_for_an_output_folder(argv, option, places, capsys):
    argv = [a.replace("{tmp}", str(places)) for a in argv]
    err = cli_error([*argv, places / "afile"], capsys)
    assert err == (
        f"reform-sim {argv[0]}: error: {option} {places / 'afile'}: "
        "expected a folder path, found an existing file"
    )


def test_an_experiment_report_that_is_a_folder(places, capsys):
    (places / "rep" / "paper-experiment.md").mkdir(parents=True)
    argv = ["experiment", "paper", "--data", "salsa=s", "--data", "babble=b"]
    err = cli_error([*argv, "--out", places / "rep"], capsys)
    assert err == (
        f"reform-sim experiment: error: --out {places / 'rep' / 'paper-experiment.md'}: "
        "expected a file path, found an existing folder"
    )


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
def test_train_fails_before_cross_validating_when_the_model_folder_cannot_be_made(
    toy_dataset, capsys
):
    status = main(["train", "--tune", "--data", str(toy_dataset), "--out", "/proc/x/m.skops"])
    err = capsys.readouterr().err
    assert status == 2
    assert err.startswith(
        "reform-sim train: error: --out /proc/x/m.skops: folder /proc/x cannot be created"
    )
    assert "cross-validating" not in err and len(err.strip().splitlines()) == 1


def test_save_must_be_an_rrd_file_before_the_run(tmp_path, capsys):
    missing = tmp_path / "missing.parquet"  # never read: the flags are checked first
    err = cli_error(
        ["evaluate", "--detector", "majority", "--data", missing, "--save", tmp_path / "x.txt"],
        capsys,
    )
    assert err == (
        f"reform-sim evaluate: error: --save must be a path ending in .rrd, got "
        f"'{tmp_path / 'x.txt'}'"
    )


def test_an_empty_output_path_is_refused(toy_dataset, capsys):
    argv = ["evaluate", "--detector", "majority", "--data", toy_dataset, "--out", ""]
    assert (
        cli_error(argv, capsys)
        == "reform-sim evaluate: error: --out: expected a path, found an empty one"
    )

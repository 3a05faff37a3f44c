"""Options that conflict, or that a command would ignore, are errors naming both options; every
``--jobs`` is checked alike, up front; unreadable input files are named."""

from __future__ import annotations

import json

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


@pytest.mark.parametrize("command", ["evaluate", "detect"])
@pytest.mark.parametrize(
    ("options", "message"),
    [
        (
            ["--detector", "majority", "--model", "m.skops"],
            "--model is an option of --detector reform, not of --detector majority",
        ),
        (
            ["--detector", "majority", "--stride", "0.5"],
            "--stride is an option of --detector gcff, not of --detector majority",
        ),
        (
            ["--detector", "gcff", "--model", "m.skops"],
            "--model is an option of --detector reform, not of --detector gcff",
        ),
        (
            ["--model", "m.skops", "--stride", "0.5", "--gcff-orientation", "head"],
            "--stride is an option of --detector gcff, not of --detector reform",
        ),
    ],
)
def test_an_option_of_another_detector_is_ancli_error(
    command, options, message, toy_dataset, tmp_path, capsys
):
    argv = [command, *options, "--data", toy_dataset]
    if command == "detect":
        argv += ["--out", tmp_path / "groups.json"]
    assert cli_error(argv, capsys) == f"reform-sim {command}: error: {message}"
    assert not (tmp_path / "groups.json").exists()


def test_gcff_options_still_reach_gcff(toy_dataset, tmp_path, capsys):
    out = tmp_path / "groups.json"
    argv = ["detect", "--detector", "gcff", "--stride", "0.6", "--gcff-orientation", "body"]
    assert main([*argv, "--data", str(toy_dataset), "--out", str(out)]) == 0, capsys.readouterr()
    params = json.loads(out.read_text())["detector_params"]
    assert (params["stride"], params["orientation"]) == (0.6, "body")


def test_train_fraction_needs_a_split(toy_dataset, tmp_path, capsys):
    model = tmp_path / "m.skops"
    argv = ["train", "--data", toy_dataset, "--classifier", "logistic-regression", "--out", model]
    err = cli_error([*argv, "--train-fraction", "0.3"], capsys)
    assert err == (
        "reform-sim train: error: --train-fraction 0.3 splits the frames for --frames "
        "train|test; with --frames all every annotated frame counts"
    )
    assert not model.exists()
    assert main([str(a) for a in [*argv, "--train-fraction", "0.3", "--frames", "train"]]) == 0
    assert "on 6 frames of toy" in capsys.readouterr().out  # 30 % of 20 frames


def test_generate_rejects_jobs_with_ray(tmp_path, capsys):
    argv = ["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "0"]
    err = cli_error([*argv, "--out", tmp_path / "g", "--backend", "ray", "--jobs", "1"], capsys)
    assert err.startswith("reform-sim generate: error: --jobs sets local worker processes")
    assert "--backend ray" in err
    assert not (tmp_path / "g").exists()


JOBS_COMMANDS = [
    ["train", "--tune", "--data", "{data}", "--out", "{tmp}/m.skops"],
    ["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "0", "--out", "{tmp}/g"],
    ["stress", "--grid", "small", "--out", "{tmp}/s"],
    ["demo", "--quick", "--out", "{tmp}/d"],
    ["experiment", "hri", "--out", "{tmp}/h"],
    ["experiment", "paper", "--data", "salsa=s", "--data", "babble=b", "--out", "{tmp}/p"],
    ["experiment", "sim2real", "--data", "salsa=s", "--data", "babble=b", "--out", "{tmp}/r"],
]


@pytest.mark.parametrize("jobs", ["0", "-2"])
@pytest.mark.parametrize("argv", JOBS_COMMANDS, ids=lambda argv: "-".join(argv[:2]))
def test_jobs_below_one_is_refused_up_front(argv, jobs, toy_dataset, tmp_path, capsys):
    argv = [a.replace("{data}", str(toy_dataset)).replace("{tmp}", str(tmp_path)) for a in argv]
    err = cli_error([*argv, "--jobs", jobs], capsys)
    assert err == f"reform-sim {argv[0]}: error: --jobs must be >= 1, got {jobs}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["toy.parquet"]


def test_notes_that_are_not_text_name_the_file(toy_dataset, tmp_path, capsys):
    notes = tmp_path / "notes.md"
    notes.write_bytes(b"# Notes\n\xff\xfe binary")
    report = tmp_path / "reports" / "characterisation.md"
    argv = ["characterize", "--data", toy_dataset, "--out", report.parent, "--notes", notes]
    err = cli_error(argv, capsys)
    assert err == (
        f"reform-sim characterize: error: --notes {notes}: expected UTF-8 Markdown text, "
        "found byte 0xff at offset 8 that is not UTF-8"
    )
    assert not report.exists()


def test_with_results_that_are_not_text_name_the_file(tmp_path, capsys):
    results = tmp_path / "results.json"
    results.write_bytes(b"\x89PNG\r\n")
    argv = [
        "experiment",
        "gcff",
        "--data",
        "salsa=s",
        "--data",
        "babble=b",
        "--out",
        tmp_path / "x",
    ]
    err = cli_error([*argv, "--with-results", results], capsys)
    assert err == (
        f"reform-sim experiment: error: --with-results {results}: expected JSON text, found "
        "byte 0x89 at offset 0 that is not UTF-8"
    )


def test_the_parsers_formats_and_units_are_the_loaders():
    from reform.datasets import FORMATS, LENGTH_UNITS
    from reform.datasets.detect import FORMAT_ALIASES
    from sim.cli import _common

    assert set(_common.FORMATS) == set(FORMATS) | set(FORMAT_ALIASES)
    assert _common.LENGTH_UNITS == LENGTH_UNITS


def test_a_system_error_is_one_line_naming_the_path(tmp_path, capsys):
    from sim.cli import main

    # A path whose name is too long for the file system: the system refuses it (OSError).
    long = tmp_path / ("x" * 300)
    assert main(["data", "info", "--data", str(long / "features.txt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("reform-sim data: error: ") and err.count("\n") == 1


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["simulate", "--scenario", "mingle", "--seed", "1", "--duration", "abc"],
            "reform-sim simulate: error: argument --duration: invalid float value: 'abc' "
            "(see reform-sim simulate --help)",
        ),
        (
            ["stress", "--episodes", "1e9"],
            "reform-sim stress: error: argument --episodes: invalid int value: '1e9' "
            "(see reform-sim stress --help)",
        ),
        (
            ["data"],
            "reform-sim data: error: the following arguments are required: ACTION "
            "(see reform-sim data --help)",
        ),
        (["nope"], "reform-sim: error: argument COMMAND: invalid choice: 'nope' "),
    ],
    ids=["float", "int", "missing", "command"],
)
def test_a_malformed_command_line_is_one_line(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(message), err

"""Inputs that would have run and given something other than what was asked: refused in one
line before any work (a value given twice, an annotation that erases the scene, an output name
of another format, a folder holding a file that is none of its dataset's shards)."""

from __future__ import annotations

import gymnasium as gym
import pytest
from cli_errors import cli_error, run_cli
from toy_scenes import toy_frames

import sim.envs  # noqa: F401  (registers the environments)
from reform import Dataset, write_parquet
from sim.cli import main

GENERATE = ["generate", "--scenario", "mingle", "--episodes", "1", "--set", "people=6", "-q"]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            ["--duration", "5", "--set", "duration=10"],
            "--duration 5 and --set duration=10 both give the episode's length; give one",
        ),
        (
            ["--duration", "5", "--annotation", "dropout=1"],
            "annotation dropout must be below 1 (1 drops everyone from every frame), got 1.0",
        ),
        (
            ["--duration", "5", "--annotation", "min_group_seconds=100"],
            "annotation min_group_seconds must be shorter than the episodes (5 s), got 100",
        ),
    ],
    ids=["duration-twice", "everyone-dropped", "no-group-ever-called"],
)
def test_generate_refuses_what_would_not_be_what_was_asked(extra, message, tmp_path, capsys):
    out = tmp_path / "d"
    assert message in cli_error([*GENERATE, *extra, "--out", out], capsys)
    assert not out.exists()


def test_generate_refuses_a_rate_off_the_control_steps_before_making_the_folder(tmp_path, capsys):
    out = tmp_path / "d"
    line = cli_error([*GENERATE, "--duration", "10", "--rate", "3", "--out", out], capsys)
    assert line.endswith(
        "--rate 3: expected a rate whose period is a whole number of 0.01 s control steps "
        "(e.g. 1, 2, 4, 5, 10), found 3"
    )
    assert not out.exists()


def test_generate_sizes_a_long_set_duration_before_planning_it(tmp_path, capsys):
    out = tmp_path / "d"
    argv = ["generate", "--scenario", "mingle", "--episodes", "1", "--set", "people=4", "-q"]
    argv += ["--set", "duration=86400", "--jobs", "1", "--max-memory", "1M", "--out", out]
    line = cli_error(argv, capsys)
    assert "172,800 frames of 4 agents" in line
    assert "more than the limit --max-memory 1 MiB" in line
    assert "(fewer --episodes, a shorter --set duration or a lower --rate)" in line
    assert not out.exists()


def test_generate_refuses_a_folder_holding_a_file_that_is_none_of_its_shards(tmp_path, capsys):
    out = tmp_path / "d"
    argv = [*GENERATE, "--duration", "5", "--out", out]
    assert run_cli(argv, capsys)[0] == 0
    stray = out / "data" / "scenario=mingle" / "extra.parquet"
    stray.write_bytes((out / "data/scenario=mingle/episode=0/part.parquet").read_bytes())
    more = [*GENERATE[:4], "2", *GENERATE[5:], "--duration", "5", "--out", out]
    assert cli_error(more, capsys).endswith(
        f"--out {out} holds data/scenario=mingle/extra.parquet, which is none of the shards "
        "of this dataset (2 episodes of mingle, as scenario=mingle/episode=0/part.parquet ...): "
        "remove it or use another folder"
    )
    assert not (out / "data/scenario=mingle/episode=1").exists()  # refused before any work


@pytest.fixture
def toy_dataset(tmp_path):
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 20)), name="toy", source="toy_scenes"), path)
    return path


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["data", "convert", "--out", "conv.csv"], "--out conv.csv: expected a file name ending "),
        (["train", "--features", "", "--out", "m.skops"], "--features must name features among"),
        (
            ["train", "--out", "m.txt"],
            "--out m.txt: expected a file name ending in .skops (the format written), found .txt",
        ),
        (
            ["train", "--detector", "dante", "--out", "m.skops"],
            "--out m.skops: expected a file name ending in .safetensors (the format written), "
            "found .skops",
        ),
    ],
    ids=["convert-to-csv", "no-features", "reform-model-as-text", "dante-model-as-skops"],
)
def test_outputs_and_features_say_what_they_are(argv, message, toy_dataset, tmp_path, capsys):
    argv = [a if a not in ("conv.csv", "m.txt", "m.skops") else tmp_path / a for a in argv]
    err = cli_error([*argv, "--data", toy_dataset], capsys)
    for name in ("conv.csv", "m.txt", "m.skops"):
        message = message.replace(f"{name}:", f"{tmp_path / name}:")
    assert message in err
    assert not list(tmp_path.glob("conv.csv")) and not list(tmp_path.glob("m.*"))


def test_an_environments_record_dir_that_is_a_file_is_refused_when_made(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("")
    with pytest.raises(ValueError, match=rf"^record_dir {afile}: expected a folder path"):
        gym.make("ReformSim/HRIConversation-v0", record_dir=afile)


@pytest.mark.parametrize("experiment", ["gcff", "paper"])
def test_an_experiments_data_says_what_it_takes(experiment, toy_dataset, tmp_path, capsys):
    salsa = "a folder with the DANTE text files features.txt and group_names.txt"
    for given, found in (
        (tmp_path / "some" / "file.parquet", "no such file or folder"),
        (toy_dataset, "a dataset in the parquet format"),
    ):
        argv = ["experiment", experiment, "--data", f"salsa={given}", "--out", tmp_path / "out"]
        assert cli_error(argv, capsys) == (
            f"reform-sim experiment: error: --data salsa={given}: expected {salsa} (or a "
            f"dataset's name), found {found}"
        )
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("annotated", "extra", "part"),
    [
        (0, [], "the dataset"),
        (1, ["--test-split", "raw.parquet"], "the test part of the dataset's time split"),
    ],
    ids=["none-annotated", "test-part-not-annotated"],
)
def test_benchmark_refuses_a_dataset_with_nothing_to_score(
    annotated, extra, part, toy_dataset, tmp_path, capsys
):
    raw = tmp_path / "raw.parquet"
    frames = [
        f if k < annotated else f.replace(groups=None) for k, f in enumerate(toy_frames(0, 20))
    ]
    write_parquet(Dataset(frames=tuple(frames), name="raw", source="toy_scenes"), raw)
    out = tmp_path / "bench"
    argv = ["benchmark", "--data", toy_dataset, "--data", raw, *extra, "--detector", "majority"]
    assert cli_error([*argv, "--out", out, "--no-recordings"], capsys) == (
        f"reform-sim benchmark: error: {raw}: {part} has no annotated frames to score"
    )
    assert not out.exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["twin", "--data", "synth", "--out", "OUT", "--seed", "99999999999999999999999"],
        ["generate", "--scenario", "mingle", "--episodes", "1", "--out", "OUT", "--seed", "1.5"],
        ["stress", "--grid", "small", "--out", "OUT", "--seed", "-1"],
        ["demo", "--quick", "--out", "OUT", "--seed", "-1"],
    ],
    ids=["twin-beyond-64-bits", "generate-not-whole", "stress-negative", "demo-negative"],
)
def test_a_seed_no_later_command_would_take_is_refused_as_it_is_read(argv, tmp_path, capsys):
    from sim.cli._grammar import MAX_SEED
    from sim.twins.description import MAX_SEED as KEPT

    assert MAX_SEED == KEPT  # a twin file keeps any seed a command takes
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as stopped:  # refused as the command line is read
        run_cli([str(out) if word == "OUT" else word for word in argv], capsys)
    assert stopped.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"reform-sim {argv[0]}: error: argument --seed: expected a whole number")
    assert f"from 0 to {MAX_SEED}, found '{argv[-1]}'" in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "1", "--seed=2"],
            "--seed is given twice (--seed 1, then --seed 2); give it once",
        ),
        (
            ["tune", "--twin", "t.json", "--detector", "gcff", "--detector", "reform"],
            "--detector is given twice (--detector gcff, then --detector reform); give it once",
        ),
    ],
    ids=["seed", "tune-detector"],
)
def test_an_option_of_one_value_given_twice_is_refused_not_read_as_the_last(
    argv, message, tmp_path, capsys
):
    out = tmp_path / "out"
    err = cli_error([*argv, "--out", out], capsys)
    assert err == f"reform-sim {argv[0]}: error: {message}"
    assert not out.exists()



@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["generate", "--scenario", "mingle", "--episodes=\u0663"], "argument --episodes: invalid "
         "int value: '\u0663'"),
        (["generate", "--scenario", "mingle", "--episodes", "1", "--set", "people=\u0663"],
         "mingle: option people must be an integer, got '\u0663'"),
        (["evaluate", "--detector", "gcff", "--stride", "\u0663", "--data", "x"], "argument "
         "--stride: invalid float value: '\u0663'"),
        (["generate", "--scenario", "mingle", "--episodes", "1", "--seed", "\u0663"], "argument "
         "--seed: expected a whole number from 0"),
    ],
    ids=["episodes", "scenario-option", "detector-option", "seed"],
)  # fmt: skip
def test_digits_of_other_scripts_are_refused_not_read_as_ascii(argv, message, tmp_path, capsys):
    # int('\u0663') is 3: a count typed in another script is refused, not read as one
    try:
        status = main([*argv, "--out", str(tmp_path / "out")])
    except SystemExit as stop:  # argparse's own refusal
        status = stop.code
    err = capsys.readouterr().err.strip()
    assert status == 2 and len(err.splitlines()) == 1, err
    assert message in err
    assert not (tmp_path / "out").exists()

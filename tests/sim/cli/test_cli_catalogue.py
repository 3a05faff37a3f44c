"""The command line reads the detector catalogue: every catalogued detector and its declared
options appear in --help; any detector's options come as --option NAME=VALUE or from a settings
file (reform.settings); a settings file names its detector."""

from __future__ import annotations

import json

import pytest
from cli_errors import cli_error
from toy_scenes import toy_frames

from reform import Dataset, detector_info, detector_names, write_parquet, write_settings
from sim.cli import main


@pytest.fixture
def toy_dataset(tmp_path):
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 20)), name="toy", source="toy_scenes"), path)
    return path


@pytest.mark.parametrize("command", ["evaluate", "detect"])
def test_help_lists_every_catalogued_detector_and_its_options(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])

    def bare(text: str) -> str:  # argparse wraps lines at spaces and after hyphens
        return "".join(text.split())

    text = bare(capsys.readouterr().out)
    for name in detector_names():
        info = detector_info(name)
        assert bare(f"{name}: {info.help}") in text
        for option in info.options:
            assert bare(option.describe()) in text


def test_a_settings_file_names_its_detector(toy_dataset, tmp_path):
    settings = write_settings(tmp_path / "gcff.json", "gcff", {"stride": 0.55, "mdl": 0.4})
    out = tmp_path / "groups.json"
    argv = ["detect", "--settings", settings, "--data", toy_dataset, "--out", out]
    assert main([str(a) for a in argv]) == 0
    result = json.loads(out.read_text())
    assert result["detector"] == "gcff"
    assert (result["detector_params"]["stride"], result["detector_params"]["mdl"]) == (0.55, 0.4)


def test_an_option_overrides_nothing_silently(toy_dataset, tmp_path, capsys):
    settings = write_settings(tmp_path / "gcff.json", "gcff", {"stride": 0.55})
    out = tmp_path / "groups.json"
    argv = ["detect", "--settings", settings, "--option", "mdl=0.4", "--data", toy_dataset]
    assert main([str(a) for a in [*argv, "--out", out]]) == 0, capsys.readouterr().err
    params = json.loads(out.read_text())["detector_params"]
    assert (params["stride"], params["mdl"]) == (0.55, 0.4)


def test_settings_of_another_detector_are_refused(toy_dataset, tmp_path, capsys):
    settings = write_settings(tmp_path / "gcff.json", "gcff", {"stride": 0.55})
    argv = ["evaluate", "--detector", "majority", "--settings", settings, "--data", toy_dataset]
    assert cli_error(argv, capsys).endswith(
        f"--settings {settings} holds settings of detector 'gcff', not of --detector majority"
    )


def test_a_gcff_mat_file_is_for_gcff_only(toy_dataset, tmp_path, capsys):
    argv = ["evaluate", "--detector", "majority", "--settings", "s.mat", "--data", toy_dataset]
    assert "a GCFF settings_gc.mat is read by --detector gcff only" in cli_error(argv, capsys)


def test_an_option_of_a_detector_without_it_is_one_line(toy_dataset, capsys):
    argv = ["evaluate", "--detector", "majority", "--option", "k=3", "--data", toy_dataset]
    assert cli_error(argv, capsys).endswith(
        "detector 'majority' has no option 'k'; its options: none"
    )


def test_an_option_in_the_settings_file_and_on_the_command_line_is_refused(
    toy_dataset, tmp_path, capsys
):
    settings = write_settings(tmp_path / "gcff.json", "gcff", {"stride": 0.55})
    argv = ["evaluate", "--settings", settings, "--stride", "0.5", "--data", toy_dataset]
    assert cli_error(argv, capsys).endswith(
        f"--detector gcff: option stride is given twice (0.55 by --settings {settings}, 0.5 "
        "besides); give it once"
    )


def test_a_settings_file_beside_a_model_file_is_not_left_unread(toy_dataset, tmp_path, capsys):
    settings = write_settings(tmp_path / "gcff.json", "gcff", {"stride": 0.55})
    argv = ["evaluate", "--settings", settings, "--model", "m.skops", "--data", toy_dataset]
    assert cli_error(argv, capsys).endswith(
        f"--settings {settings} holds settings of detector 'gcff', not of --detector reform"
    )


def test_reforms_model_comes_as_its_option_or_in_its_settings_file(toy_dataset, tmp_path, capsys):
    from reform import Reform, save_model

    model = save_model(Reform().fit(toy_frames(0, 20)), tmp_path / "m.skops")
    settings = write_settings(tmp_path / "reform.json", "reform", {"model": str(model)})
    for how in (["--settings", settings], ["--detector", "reform", "--option", f"model={model}"]):
        out = tmp_path / "groups.json"
        argv = ["detect", *how, "--data", toy_dataset, "--out", out]
        assert main([str(a) for a in argv]) == 0, capsys.readouterr().err
        assert json.loads(out.read_text())["detector"] == "reform"
        out.unlink()
    capsys.readouterr()
    argv = ["evaluate", "--settings", settings, "--model", model, "--data", toy_dataset]
    assert "option model is given twice" in cli_error(argv, capsys)

"""Venue twins: fitted without labels, refused on bad input, frozen in a checked twin.json."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from reform.datasets import write_parquet
from reform.frame import Dataset, Frame
from sim.twins import (
    TwinFormatError,
    TwinInputError,
    fit_twin,
    measure_place,
    read_twin,
    write_twin,
)
from tests.cli_errors import cli_error, run_cli


def _frames(*, n_frames: int = 24, people: int = 6, scale: float = 1.0, seed: int = 3) -> list:
    """A small recording: people standing in two clusters with jitter, 1 frame per second,
    yaws coded in 8 directions, annotated with two groups."""
    rng = np.random.default_rng(seed)
    base = rng.uniform(-2.0, 2.0, size=(people, 2))
    yaw0 = rng.uniform(-np.pi, np.pi, size=people)
    step = 2 * np.pi / 8
    frames = []
    half = people // 2
    for t in range(n_frames):
        position = (base + rng.normal(0.0, 0.02, size=base.shape)) * scale
        yaw = np.round((yaw0 + rng.normal(0, 0.1, people)) / step) * step
        yaw = (yaw + np.pi) % (2 * np.pi) - np.pi
        groups = (tuple(range(1, half + 1)), tuple(range(half + 1, people + 1)))
        frames.append(
            Frame(
                ids=np.arange(1, people + 1),
                position=position,
                yaw=yaw,
                groups=groups,
                time=float(t),
                sequence="s",
            )  # fmt: skip
        )
    return frames


@pytest.fixture(scope="module")
def fitted(place_twin):
    """The twin of ``_frames(scale=1.5)`` (fitted once for the session)."""
    return place_twin


def _shuffled_groups(frames: list[Frame]) -> list[Frame]:
    """The frames with other groups: two drawn at random in each frame."""
    rng = np.random.default_rng(0)
    shuffled = []
    for f in frames:
        ids = rng.permutation(f.ids)
        shuffled.append(f.replace(groups=(tuple(ids[:2].tolist()), tuple(ids[2:5].tolist()))))
    return shuffled


def test_a_twin_file_reads_back_as_written(place_twin, tmp_path):
    # (that a twin never reads the groups: test_the_twin_command_writes_the_twin_and_its_plots)
    path = write_twin(place_twin, tmp_path / "0.json")
    assert read_twin(path).to_json() == json.loads(path.read_text())  # round trip


def test_use_labels_is_a_mode_of_its_own(fitted):
    twin = fit_twin(_frames(scale=1.5), name="place", use_labels=True)
    assert twin.mode == "labels" and fitted.mode == "label-free"
    assert "options.alone_share" in [f.name for f in twin.fitted]
    assert twin.options["radius_base"] != fitted.options["radius_base"]  # fitted on the groups


def test_use_labels_without_groups_is_refused_not_fitted_label_free():
    frames = _frames(scale=1.5)
    with pytest.raises(TwinInputError, match=r"^place: field groups: expected annotated frames "
                       r"with a group of two or more .* found no annotated frame$"):  # fmt: skip
        fit_twin([f.replace(groups=None) for f in frames], name="place", use_labels=True)
    alone = [f.replace(groups=tuple((int(i),) for i in f.ids)) for f in frames]
    with pytest.raises(TwinInputError, match=rf"found none in its {len(frames)} annotated frames"):
        fit_twin(alone, name="place", use_labels=True)


def test_a_twin_matches_the_recording_it_is_fitted_to(fitted):
    real = measure_place(_frames(scale=1.5))
    assert fitted.options["people"] == 6
    assert fitted.annotation.directions == 8  # the recording's coding, found
    assert fitted.rate_hz == pytest.approx(1.0)
    assert fitted.statistics["twin"]["nn_median"] == pytest.approx(real.nn_median, rel=0.35)
    fields = {f.name for f in fitted.fitted}
    assert {"options.people", "annotation.scale", "options.spacing"} <= fields


@pytest.mark.parametrize(
    ("frames", "message"),
    [
        (_frames(n_frames=9), r"place: field frames: expected at least 10 frames .* found 9"),
        (
            [
                f.replace(
                    ids=f.ids[:1], position=f.position[:1], yaw=f.yaw[:1], kinds=None, groups=None
                )
                for f in _frames()
            ],
            r"place: field ids: expected two or more people in some frame, found at most 1",
        ),
        (_frames(scale=0.01), r"place: field position: expected a median nearest-neighbour"),
        (_frames(scale=100.0), r"found \d+(\.\d+)? \(positions in another unit"),
    ],
    ids=["too-few-frames", "never-two-people", "centimetres-as-metres", "metres-as-centimetres"],
)
def test_bad_recordings_are_refused_before_any_work(frames, message):
    with pytest.raises(TwinInputError, match=message):
        fit_twin(frames, name="place")


@pytest.fixture(scope="module")
def twin_file(fitted, tmp_path_factory) -> Path:
    return write_twin(fitted, tmp_path_factory.mktemp("t") / "t.json")


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(colour="red"), r"field colour: expected one of the fields"),
        (lambda d: d.update(version=99), r"field version: expected 1 .* found 99"),
        (lambda d: d.update(rate_hz=-1), r"field rate_hz: expected a number in \(0, 100\]"),
        (lambda d: d.update(rate_hz=3), r"field rate_hz: expected a rate whose period is a whole"),
        (lambda d: d.update(episodes=0), r"field episodes: expected a whole number from 1"),
        (lambda d: d["options"].update(people=1), r"field options: .*people"),
        (lambda d: d["options"].update(wings=2), r"field options: .*wings"),
        (lambda d: d["annotation"].update(dropout=2.0), r"field annotation: .*dropout"),
        (lambda d: d["annotation"].update(blur=1), r"field annotation.blur: expected one of"),
        (lambda d: d.update(scenario="moon"), r"field scenario: expected a registered scenario"),
        (lambda d: d["options"].pop("duration"), r"field options.duration: expected a value"),
        (lambda d: d.update(annotation={}), r"field annotation.orientation: expected a value"),
        (lambda d: d["annotation"].update(scale=1e9), r"field annotation: .*scale .*at most 10000"),
        (lambda d: d["annotation"].update(position_noise=1e9), r"field annotation: .*at most 10,"),
        (lambda d: d["options"].update(people=100), r"field options: mingle: 100 people do not "),
        (lambda d: d.update(version=True), r"field version: expected 1 .* found True"),
        (lambda d: d.update(version=1.0), r"field version: expected 1 .* found 1\.0"),
        (
            lambda d: d["annotation"].update(directions=10**400),
            r"field annotation: .*directions must be at most 3600",
        ),
        (lambda d: d["annotation"].update(yaw_noise=1e300), r"field annotation: .*at most 6\.28"),
        (
            lambda d: d.update(rate_hz=1e-300),
            r"field rate_hz: expected a rate at which an episode of options.duration [\d.]+ s "
            r"holds a frame \(at least [\d.e-]+ Hz\), found 1e-300$",
        ),
        (
            lambda d: d["annotation"].update(min_group_seconds=1e308),
            r"field annotation.min_group_seconds: expected less than an episode "
            r"\(options.duration [\d.]+ s\), found 1e\+308$",
        ),
    ],
    ids=[
        "unknown-field",
        "unknown-version",
        "rate",
        "rate-off-the-control-steps",
        "episodes",
        "option-range",
        "unknown-option",
        "annotation-range",
        "unknown-annotation",
        "unknown-scenario",
        "option-left-out",
        "annotation-left-out",
        "scale-too-large",
        "jitter-too-large",
        "options-that-do-not-fit-together",
        "version-true",
        "version-not-whole",
        "directions-too-many",
        "yaw-jitter-too-large",
        "rate-too-low-for-a-frame",  # was generate's line, naming no twin file
        "min-group-longer-than-an-episode",
    ],  # fmt: skip
)
def test_a_twin_file_edited_into_nonsense_is_refused(twin_file, tmp_path, edit, message):
    data = json.loads(twin_file.read_text())
    edit(data)
    path = tmp_path / "twin.json"
    path.write_text(json.dumps(data))
    with pytest.raises(TwinFormatError, match=str(path).replace(".", r"\.") + ": " + message):
        read_twin(path)


def test_a_field_given_twice_is_refused_not_read_as_the_last(twin_file, tmp_path):
    text = twin_file.read_text().replace('"people": ', '"people": 3, "people": ', 1)
    path = tmp_path / "twin.json"
    path.write_text(text)
    with pytest.raises(TwinFormatError, match=r"field people: expected the field once, found 'it"):
        read_twin(path)


def test_a_file_that_is_not_json_is_one_line(tmp_path):
    path = tmp_path / "twin.json"
    path.write_text("{nope")
    with pytest.raises(TwinFormatError, match=r"expected a twin file \(JSON\)"):
        read_twin(path)


def test_the_twin_command_writes_the_twin_and_its_plots(place_twin, tmp_path, capsys):
    # place_twin's recording with its groups shuffled, its pilot parties on two processes (the
    # fixture's ran in one): the same twin, byte for byte. So the twin never reads the groups.
    data = tmp_path / "place.parquet"
    frames = tuple(_shuffled_groups(_frames(scale=1.5)))
    assert [f.groups for f in frames] != [f.groups for f in _frames(scale=1.5)]
    write_parquet(Dataset(frames, name="place"), data)
    argv = ["twin", "--data", data, "--out", tmp_path / "twin", "--jobs", 2, "--quiet"]
    status, out, err = run_cli(argv, capsys)
    assert status == 0, err
    assert err == ""  # --quiet, as every command that shows its progress takes it
    written = (tmp_path / "twin" / "twin.json").read_bytes()
    assert written == write_twin(place_twin, tmp_path / "fixture.json").read_bytes()
    assert read_twin(tmp_path / "twin" / "twin.json").options["people"] == 6
    assert (tmp_path / "twin" / "twin.png").read_bytes()[:4] == b"\x89PNG"
    assert "annotation.scale" in out
    # The crowd options searched together name their statistic, written out once below them.
    assert "options.spacing" in out and "searched on statistic [a]" in out
    assert out.count("spacing shape:") == 1 and out.count("    real [") == 1


def test_the_twin_command_refuses_a_small_recording_in_one_line(tmp_path, capsys):
    data = tmp_path / "small.parquet"
    write_parquet(Dataset(tuple(_frames(n_frames=5)), name="small"), data)
    line = cli_error(["twin", "--data", data, "--out", tmp_path / "twin"], capsys)
    assert "field frames: expected at least 10 frames to fit a twin, found 5" in line
    assert not (tmp_path / "twin" / "twin.json").exists()

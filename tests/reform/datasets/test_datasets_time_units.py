"""Time stamps read in their own unit, pixel folders refused unless their unit is given, and
DANTE files without orientation refused as such: small GCFF and DANTE files written here, then
the real datasets, which load as before."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from reform import DataFormatError
from reform.datasets import load_dante, load_dataset, load_gcff
from reform.datasets._validation import TIME_UNITS
from sim.cli import _common, main

# Three people in centimetres, a pair 1 m apart and a third 6.4 m away; the pair is a group.
PEOPLE = [[1, 100.0, 0.0, np.pi], [2, 0.0, 0.0, 0.0], [3, 500.0, 400.0, 0.0]]


def _cell(items) -> np.ndarray:
    array = np.empty((1, len(items)), dtype=object)
    for k, item in enumerate(items):
        array[0, k] = item
    return array


def _gcff(folder: Path, stamps, *, people=PEOPLE) -> Path:
    """A GCFF folder of one frame of ``people`` per time stamp, every frame annotated."""
    folder.mkdir(parents=True, exist_ok=True)
    stamps = np.asarray(stamps, dtype=np.float64)[None, :]
    features = _cell([np.asarray(people, dtype=np.float64)] * stamps.size)
    scipy.io.savemat(folder / "features.mat", {"features": features, "timestamp": stamps})
    gt = _cell([_cell([np.array([[1.0, 2.0]])])] * stamps.size)
    scipy.io.savemat(folder / "groundtruth.mat", {"GTgroups": gt, "GTtimestamp": stamps})
    return folder


# 2023-11-14 22:13:20 UTC, a Unix time in seconds, and frames 0.2 s apart (5 Hz).
UNIX_S = 1_700_000_000.0
STEP_S = 0.2


@pytest.mark.parametrize("unit", ["s", "ms", "us", "ns"])
def test_unix_times_are_read_in_their_unit_from_the_start(tmp_path, unit):
    per_second = 1.0 / TIME_UNITS[unit]
    stamps = (UNIX_S + STEP_S * np.arange(4)) * per_second
    dataset = load_gcff(_gcff(tmp_path / unit, stamps))
    times = [f.time for f in dataset.frames]
    np.testing.assert_allclose(times, [0.0, 0.2, 0.4, 0.6], atol=1e-6)
    assert [f.groups for f in dataset.frames] == [((1, 2),)] * 4  # ground truth still matched
    entry = dataset.metadata["report"]["time_unit"]
    assert (entry["unit"], entry["how"]) == (unit, "inferred")
    assert entry["origin_unix_s"] == {unit: pytest.approx(UNIX_S)}
    word = {"s": "seconds", "ms": "milliseconds", "us": "microseconds", "ns": "nanoseconds"}[unit]
    assert dataset.metadata["time"] == (
        f"timestamp of features.mat in Unix {word} (inferred from their magnitude and "
        "spacing), counted in seconds from each sequence's first frame"
    )


def test_frame_numbers_and_seconds_are_kept_as_stored(tmp_path):
    # The public GCFF sets number their frames 1, 2, ...; nothing is inferred or reported.
    dataset = load_gcff(_gcff(tmp_path / "numbers", [1, 2, 3]))
    assert [f.time for f in dataset.frames] == [1.0, 2.0, 3.0]
    assert dataset.metadata["time"] == "timestamp as stored in features.mat"
    assert "time_unit" not in dataset.metadata["report"]


def test_each_sequence_counts_from_its_own_start(tmp_path):
    root = tmp_path / "set"
    _gcff(root / "Seq1", (UNIX_S + STEP_S * np.arange(2)) * 1e6)
    _gcff(root / "Seq2", (UNIX_S + 3600.0 + STEP_S * np.arange(2)) * 1e6)
    dataset = load_gcff(root)
    assert [(f.sequence, round(f.time, 6)) for f in dataset.frames] == [
        ("Seq1", 0.0),
        ("Seq1", 0.2),
        ("Seq2", 0.0),
        ("Seq2", 0.2),
    ]
    origins = dataset.metadata["report"]["time_unit"]["origin_unix_s"]
    assert origins == {"Seq1": pytest.approx(UNIX_S), "Seq2": pytest.approx(UNIX_S + 3600.0)}


def test_a_stated_unit_is_trusted(tmp_path):
    # Milliseconds from the recording's start (25 Hz) look like seconds 40 s apart: only the
    # caller can tell, and their word is taken.
    folder = _gcff(tmp_path / "ms", [0, 40, 80])
    assert [f.time for f in load_gcff(folder).frames] == [0.0, 40.0, 80.0]
    dataset = load_dataset(folder, time_unit="ms")
    assert [f.time for f in dataset.frames] == pytest.approx([0.0, 0.04, 0.08])
    entry = dataset.metadata["report"]["time_unit"]
    assert (entry["unit"], entry["how"], "origin_unix_s" in entry) == ("ms", "stated", False)


@pytest.mark.parametrize(
    ("stamps", "found"),
    [
        pytest.param(
            [5e10, 5e10 + 40],
            r"values 5e\+10 to 5\.000000004e\+10, a median step of 40 between frames",
            id="between-unix-windows",
        ),
        pytest.param(
            [0, 33_333, 66_666],
            r"values 0 to 66666, a median step of 3\.333e\+04 between frames",
            id="small-times-hours-apart",
        ),
        pytest.param(
            [1.7e12, 1.7e12 + 1e7],
            r"values 1\.7e\+12 to 1\.70001e\+12, a median step of 1e\+07 between frames",
            id="unix-milliseconds-hours-apart",
        ),
    ],
)
def test_times_that_fit_no_unit_are_refused(tmp_path, stamps, found):
    folder = _gcff(tmp_path / "t", stamps)
    with pytest.raises(DataFormatError) as caught:
        load_gcff(folder)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{folder / 'features.mat'}: field 'timestamp': expected times in ")
    assert message.endswith("; give their unit with time_unit= (--time-unit): s, ms, us or ns")
    assert caught.match(f"found {found};")


def test_time_unit_is_checked(tmp_path):
    folder = _gcff(tmp_path / "t", [1, 2])
    with pytest.raises(ValueError, match=r"time_unit must be one of \('s', 'ms', 'us', 'ns'\)"):
        load_gcff(folder, time_unit="min")


def test_formats_whose_times_are_seconds_refuse_a_time_unit(babble_dir):
    with pytest.raises(ValueError, match=r"time_unit: the babble format stores seconds, got 'ms'"):
        load_dataset(babble_dir, format="babble", time_unit="ms")


def test_dante_unix_microseconds(tmp_path):
    folder = tmp_path / "dante"
    folder.mkdir()
    first = 1_700_000_000_000_000
    lines = [f"{first + k * 200_000} ID_001 1.0 0.0 3.14 ID_002 0.0 0.0 0.0" for k in range(3)]
    (folder / "features.txt").write_text("\n".join(lines) + "\n")
    (folder / "group_names.txt").write_text(f"{first + 200_000} < ID_001 ID_002 >\n")
    dataset = load_dante(folder)
    assert [f.time for f in dataset.frames] == pytest.approx([0.0, 0.2, 0.4])
    assert [f.groups for f in dataset.frames] == [None, ((1, 2),), None]
    report = dataset.metadata["report"]
    assert report["time_unit"]["unit"] == "us"
    assert report["time_unit"]["origin_unix_s"] == {"session1": pytest.approx(1.7e9)}
    assert report["time"].startswith("float(t) in Unix microseconds (inferred")


def test_cli_reads_and_states_the_unit(tmp_path, capsys):
    """``data info`` of a sequence in Unix microseconds: 0.6 s long, not 6e5 s."""
    folder = _gcff(tmp_path / "us", (UNIX_S + STEP_S * np.arange(4)) * 1e6)
    assert main(["data", "info", "--data", str(folder), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["sequences"]["us"]["duration_s"] == pytest.approx(0.6)
    assert summary["report"]["time_unit"]["unit"] == "us"
    small = _gcff(tmp_path / "ms", [0, 40, 80])
    assert main(["data", "info", "--data", str(small), "--json", "--time-unit", "ms"]) == 0
    assert json.loads(capsys.readouterr().out)["sequences"]["ms"]["duration_s"] == 0.08


def test_the_cli_offers_the_time_units_of_the_loaders():
    assert _common.TIME_UNITS == tuple(TIME_UNITS)


# --- pixels and metres ---------------------------------------------------------------------------

# Pose estimation in image pixels: the pair 400 px apart, the third 900 px from the nearest.
PIXELS = [[1, 400.0, 300.0, np.pi], [2, 800.0, 300.0, 0.0], [3, 1700.0, 400.0, 0.0]]
# The scene of PEOPLE written in metres: the pair 1 m apart, read as centimetres, 1 cm apart.
METRES = [[person, x / 100, y / 100, theta] for person, x, y, theta in PEOPLE]


@pytest.mark.parametrize(
    ("people", "message"),
    [
        pytest.param(
            PIXELS,
            "expected centimetres, people a median of at most 300 units (3 m) from their nearest "
            "neighbour, found a median of 400 units (4 m in centimetres: image pixels?); give "
            "units='px' with metres_per_pixel (--units px --metres-per-pixel M) if the file holds "
            "pixels, units='cm' (--units cm) if it holds centimetres",
            id="pixels",
        ),
        pytest.param(
            METRES,
            "expected centimetres, people a median of at least 10 units (0.1 m) from their "
            "nearest neighbour, found a median of 1 units (0.01 m in centimetres: metres?); give "
            "units='m' (--units m) if the file holds metres, units='cm' (--units cm) if it holds "
            "centimetres",
            id="metres",
        ),
    ],
)
def test_a_folder_whose_spacing_says_another_unit_is_refused(tmp_path, people, message):
    folder = _gcff(tmp_path / "set", [1, 2], people=people)
    with pytest.raises(DataFormatError) as caught:
        load_dataset(folder)
    assert str(caught.value) == f"{folder / 'features.mat'}: field 'positions': {message}"


def test_a_pixel_folder_loads_with_its_unit(tmp_path):
    folder = _gcff(tmp_path / "pose", [1, 2], people=PIXELS)
    dataset = load_dataset(folder, units="px", metres_per_pixel=0.0025)
    np.testing.assert_allclose(dataset.frames[0].position[1], [2.0, 0.75])
    assert dataset.metadata["file_units"] == "px"
    # Stated as centimetres, the file is read so: the caller knows their data.
    assert load_dataset(folder, units="cm").frames[0].position[1].tolist() == [8.0, 3.0]


def test_a_metres_folder_loads_with_its_unit(tmp_path):
    folder = _gcff(tmp_path / "metres", [1, 2], people=METRES)
    assert load_dataset(folder, units="m").frames[0].position[0].tolist() == [1.0, 0.0]
    assert load_dataset(folder, units="cm").frames[0].position[0].tolist() == [0.01, 0.0]


def test_the_pixel_check_names_the_sequence(tmp_path):
    root = tmp_path / "set"
    _gcff(root / "S1", [1, 2])
    _gcff(root / "S2", [1, 2], people=PIXELS)
    with pytest.raises(DataFormatError, match=r"S2/features.mat: field 'positions': expected"):
        load_gcff(root)


@pytest.mark.parametrize(
    ("people", "option", "unit"),
    [
        pytest.param(PIXELS, "--units px --metres-per-pixel M", "cm", id="pixels"),
        pytest.param(METRES, "--units m", "m", id="metres"),
    ],
)
def test_the_cli_refuses_another_unit_in_one_line(tmp_path, capsys, people, option, unit):
    folder = _gcff(tmp_path / "set", [1, 2], people=people)
    assert main(["data", "info", "--data", str(folder)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and option in err
    assert main(["data", "info", "--data", str(folder), "--units", unit]) == 0


def test_benchmark_reads_the_datasets_given_in_the_units_given(tmp_path, capsys):
    folder = _gcff(tmp_path / "pose", [1, 2], people=PIXELS)
    argv = ["benchmark", "--data", str(folder), "--detector", "majority", "--no-recordings"]
    argv += ["--out", str(tmp_path / "out"), "-q"]
    assert main(argv) != 0  # pixels taken for centimetres: refused, naming the option
    assert "--units px" in capsys.readouterr().err
    assert main([*argv, "--units", "px", "--metres-per-pixel", "0.0025"]) == 0
    report = (tmp_path / "out" / "benchmark.md").read_text()
    assert "--units px --metres-per-pixel 0.0025" in report
    assert main(["benchmark", "--units", "px", "--out", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.endswith("--units says how to read the datasets given with --data; give --data")


@pytest.mark.parametrize("name", ["coffeebreak", "synth"])
def test_the_public_gcff_sets_load_as_before(shared_datasets, name):
    """No unit given: the same frames as centimetres stated (the checks pass them: medians of
    0.80 m and 0.72 m, between 0.1 m and 3 m), times the frame numbers as stored, nothing about
    time reported."""
    path = shared_datasets / name
    assumed = load_dataset(path)
    stated = load_gcff(path, units="cm")
    assert assumed.frames == stated.frames
    assert [f.time for f in assumed.frames if f.sequence == assumed.frames[0].sequence][:3] == [
        1.0,
        2.0,
        3.0,
    ]
    assert "time_unit" not in assumed.metadata["report"]


def test_salsa_times_as_before(salsa_dir):
    dataset = load_dataset(salsa_dir)
    assert dataset.frames[0].time == 0.2 and dataset.frames[1].time == 3.2
    assert dataset.metadata["report"]["time"] == "round(float(t), 1)"
    assert "time_unit" not in dataset.metadata["report"]


# --- what a file lacks -------------------------------------------------------------------------


def test_dante_positions_without_orientation_are_refused_as_such(tmp_path):
    folder = tmp_path / "positions"
    folder.mkdir()
    (folder / "features.txt").write_text(
        "0.2 ID_001 1.0 2.0 ID_002 1.5 2.0\n3.2 ID_001 1.0 2.0 ID_002 1.5 2.0 ID_003 4.0 4.0\n"
    )
    (folder / "group_names.txt").write_text("0.2 < ID_001 ID_002 >\n")
    with pytest.raises(DataFormatError) as caught:
        load_dante(folder)
    assert str(caught.value) == (
        f"{folder / 'features.txt'}: field 'orientation': expected an orientation for every "
        "person (4 fields per person, ID x y θ, or 5, ID x y body head): the detectors need "
        "where each person faces, found 3 fields per person on every line (ID x y): positions "
        "without an orientation"
    )


def test_dante_truncated_line_is_still_said_truncated(tmp_path):
    folder = tmp_path / "truncated"
    folder.mkdir()
    (folder / "features.txt").write_text(
        "0.2 ID_001 1.0 2.0\n3.2 ID_001 1.0 2.0 0.5 ID_002 1.5 2.0 0.1\n"
    )
    (folder / "group_names.txt").write_text("0.2 < ID_001 >\n")
    with pytest.raises(DataFormatError, match=r"line 1: field 'tokens': .*\(truncated line\?\)"):
        load_dante(folder)


def test_gcff_positions_without_orientation_are_refused_as_such(tmp_path):
    folder = _gcff(tmp_path / "xy", [1], people=[p[:3] for p in PEOPLE])
    with pytest.raises(
        DataFormatError,
        match=r"features.mat: frame 1: field 'features': expected an N×4 matrix \[ID, x, y, θ\]: "
        r"a position and an orientation per person, found shape \(3, 3\): \[ID, x, y\] without "
        r"the orientation θ",
    ):
        load_gcff(folder)

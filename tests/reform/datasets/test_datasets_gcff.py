"""The GCFF MATLAB loader, on folders written with scipy.io.savemat."""

from __future__ import annotations

import gzip
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from dataset_refusals import assert_refused

from reform import DataFormatError
from reform.datasets import detect_format, load_dataset, load_gcff
from reform.datasets.gcff_mat import read_settings
from reform.gcff import Gcff


def _cell(items) -> np.ndarray:
    """A 1×K MATLAB cell array."""
    array = np.empty((1, len(items)), dtype=object)
    for k, item in enumerate(items):
        array[0, k] = item
    return array


def _gt(*groups) -> np.ndarray:
    return _cell([np.array([members], dtype=np.float64) for members in groups])


# Three frames in centimetres: a pair plus a loner, one person alone, nobody.
FEATURES = [
    np.array([[1, 100.0, 200.0, 0.5], [2, 150.0, 200.0, 3.0], [7, 400.0, -50.0, -1.5]]),
    np.array([[1, 110.0, 210.0, 6.0]]),  # θ in [0, 2π): wrapped on load
    np.zeros((0, 4)),
]
TIMESTAMPS = [10, 20, 30]


def _write(
    folder: Path,
    *,
    features=None,
    timestamps=None,
    gt_groups=None,
    gt_timestamps=None,
    settings: dict | None = None,
    features_vars: dict | None = None,
    gt_vars: dict | None = None,
) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    features = FEATURES if features is None else features
    timestamps = TIMESTAMPS if timestamps is None else timestamps
    if gt_groups is None:
        # frame 10: the pair and a listed singleton; frame 20: one listed singleton; 30: none.
        gt_groups = [_gt([1, 2], [7]), _gt([1]), _cell([])]
        gt_timestamps = [10, 20, 30] if gt_timestamps is None else gt_timestamps
    features_vars = features_vars or {
        "features": _cell(features),
        "timestamp": np.array([timestamps], dtype=np.float64),
    }
    gt_vars = gt_vars or {
        "GTgroups": _cell(gt_groups),
        "GTtimestamp": np.array([gt_timestamps], dtype=np.float64),
    }
    scipy.io.savemat(folder / "features.mat", features_vars)
    scipy.io.savemat(folder / "groundtruth.mat", gt_vars)
    if settings is not None:
        scipy.io.savemat(folder / "settings_gc.mat", settings)
    return folder


def test_loads_and_converts_centimetres(tmp_path):
    folder = _write(tmp_path / "CoffeeBreak", settings={"stride": 70.0, "mdl": 30000.0})
    dataset = load_gcff(folder)
    assert dataset.name == "CoffeeBreak"
    assert [f.sequence for f in dataset] == ["CoffeeBreak"] * 3
    assert [f.time for f in dataset] == [10.0, 20.0, 30.0]
    first, second, empty = dataset
    assert first.ids.tolist() == [1, 2, 7]
    np.testing.assert_allclose(first.position, [[1.0, 2.0], [1.5, 2.0], [4.0, -0.5]])
    np.testing.assert_allclose(first.yaw, [0.5, 3.0, -1.5])
    assert first.head_position is None and first.head_yaw is None
    assert first.groups == ((1, 2),)
    assert first.partition() == ((1, 2), (7,))
    assert second.yaw[0] == pytest.approx(6.0 - 2 * np.pi)
    assert second.groups == ()
    assert empty.n_people == 0 and empty.groups == ()
    settings = dataset.metadata["settings_gc"]
    assert settings == {
        "units": "cm",
        "stride": 70.0,
        "mdl": 30000.0,
        "stride_m": 0.7,
        "mdl_m2": 3.0,
    }
    report = dataset.metadata["report"]
    assert report["annotated_frames"] == 3
    assert report["groundtruth_singletons_listed"] == 2


def test_metres(tmp_path):
    folder = _write(tmp_path / "synth", settings={"stride": 0.7})
    dataset = load_dataset(folder, units="m")
    np.testing.assert_allclose(dataset[0].position[0], [100.0, 200.0])
    assert dataset.metadata["settings_gc"]["stride_m"] == 0.7


def test_unannotated_frames_and_squeezed_shapes(tmp_path):
    # GT for frame 20 only, its groups stored as one numeric row (no inner cell).
    gt_vars = {"GTgroups": _cell([np.array([[1.0]])]), "GTtimestamp": np.array([[20.0]])}
    features = [FEATURES[0], np.array([[1.0, 0.0, 0.0, 0.0]]), FEATURES[2]]
    folder = _write(tmp_path / "one", features=features, gt_vars=gt_vars)
    dataset = load_gcff(folder)
    assert [f.annotated for f in dataset] == [False, True, False]
    assert dataset[1].groups == ()


def test_single_group_numeric_vector_and_timestamp_column(tmp_path):
    gt_vars = {"GTgroups": _cell([np.array([[1.0, 2.0]])]), "GTtimestamp": np.array([[10.0]])}
    features_vars = {"features": _cell(FEATURES), "timestamp": np.array([[10.0], [20.0], [30.0]])}
    folder = _write(tmp_path / "col", features_vars=features_vars, gt_vars=gt_vars)
    assert load_gcff(folder)[0].groups == ((1, 2),)


def test_detection(tmp_path):
    folder = _write(tmp_path / "cp")
    assert detect_format(folder) == "gcff"
    assert detect_format(folder / "features.mat") == "gcff"
    assert load_dataset(folder / "features.mat").name == "cp"


# --- bad input ---------------------------------------------------------------------------------


def test_unknown_units(tmp_path):
    folder = _write(tmp_path / "u")
    with pytest.raises(ValueError, match=r"units must be one of \('cm', 'm', 'px'\), got 'mm'"):
        load_gcff(folder, units="mm")
    with pytest.raises(ValueError, match=r"units must be one of \('cm', 'm', 'px'\), got 'inch'"):
        load_dataset(folder, units="inch")


def test_missing_files(tmp_path):
    folder = _write(tmp_path / "m1")
    (folder / "groundtruth.mat").unlink()
    assert_refused(
        load_gcff, folder, r"groundtruth.mat: expected the GCFF ground-truth file .*no such file"
    )
    assert_refused(load_gcff, tmp_path / "nowhere", r"nowhere: expected a GCFF folder")
    assert_refused(
        load_dataset, tmp_path / "nowhere", r"nowhere: expected an existing dataset file or folder"
    )


def test_empty_and_corrupt_files(tmp_path):
    folder = _write(tmp_path / "e")
    (folder / "features.mat").write_bytes(b"")
    assert_refused(
        load_gcff, folder, r"features.mat: expected the GCFF features file \(a non-empty file\)"
    )
    (folder / "features.mat").write_bytes(b"\x00\x01 not a MATLAB file at all \xff" * 10)
    assert_refused(load_gcff, folder, r"features.mat: expected a readable MATLAB .mat file")


# What a clone without Git LFS holds in place of each file, and what a web server answers for a
# file it does not have.
LFS_POINTER = (
    b"version https://git-lfs.github.com/spec/v1\n"
    b"oid sha256:31a03829bc785b1fd6540f0174a0beaab29ee17cd7b69dd38473565aab22abe6\nsize 14215\n"
)
HTML_PAGE = b"<!DOCTYPE html><html><body>404: Not Found</body></html>\n"


@pytest.mark.parametrize("name", ["features.mat", "groundtruth.mat", "settings_gc.mat"])
@pytest.mark.parametrize(
    ("content", "found"),
    [
        pytest.param(
            LFS_POINTER, "a Git LFS pointer, not the file; fetch it with `git lfs pull`", id="lfs"
        ),
        pytest.param(
            HTML_PAGE, "text starting with '<!DOCTYPE html><html', not a MATLAB file", id="html"
        ),
        pytest.param(
            gzip.compress(b"MATLAB 5.0 MAT-file" + bytes(200)),
            "a gzip-compressed file; decompress it first",
            id="gzip",
        ),
        pytest.param(
            b"MATLAB 5.0 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024",
            "a MATLAB file cut short inside its 128-byte header (76 bytes in all)",
            id="cut-in-its-header",  # its header is text: before, 'text starting with ...'
        ),
    ],
)
def test_a_text_file_in_place_of_a_mat_file_is_named(tmp_path, name, content, found):
    folder = _write(tmp_path / "text", settings={"stride": 70.0, "mdl": 10000.0})
    (folder / name).write_bytes(content)
    with pytest.raises(DataFormatError) as caught:
        load_gcff(folder)
    assert str(caught.value) == f"{folder / name}: expected a MATLAB .mat file, found {found}"


def test_missing_variable(tmp_path):
    folder = _write(tmp_path / "v", features_vars={"features": _cell(FEATURES)})
    assert_refused(
        load_gcff,
        folder,
        r"features.mat"
        r": field 'timestamp': expected a variable 'timestamp', found variables \['features'\]",
    )


def test_wrong_column_count(tmp_path):
    features = [FEATURES[0][:, :3], FEATURES[1], FEATURES[2]]
    folder = _write(tmp_path / "c", features=features)
    assert_refused(
        load_gcff,
        folder,
        r"features.mat: frame 1"
        r": field 'features': expected an N×4 matrix .*found shape \(3, 3\)",
    )


@pytest.mark.parametrize(
    ("row", "column", "value", "message"),
    [
        pytest.param(
            2,
            3,
            np.inf,
            r"frame 1, row 3: field 'θ': expected a finite number, found inf",
            id="inf",
        ),
        pytest.param(
            0,
            3,
            90.0,
            r"frame 1, row 1 \(ID 1\): field 'θ': expected radians .*degrees.*found 90.0",
            id="degrees",
        ),
        pytest.param(
            2,
            0,
            2,
            r"features.mat: frame 1: field 'ID': expected ids unique .*found id 2 twice",
            id="duplicate-ids",
        ),
        pytest.param(
            0,
            1,
            1e200,
            r"frame 1, row 1 \(ID 1\): field 'x': expected a position with \|value\| <= 1e\+10 "
            r"file units \(1e\+08 m; .*found 1e\+200",
            id="huge-position",  # centimetres: the bound is 1e8 m = 1e10 cm
        ),
    ],
)
def test_bad_feature_value(tmp_path, row, column, value, message):
    bad = FEATURES[0].copy()
    bad[row, column] = value
    folder = _write(tmp_path / "bad", features=[bad, FEATURES[1], FEATURES[2]])
    assert_refused(load_gcff, folder, message)


@pytest.mark.parametrize(
    ("gt_groups", "gt_timestamps", "message"),
    [
        pytest.param(
            [_gt([1, 2], [2, 7])],
            [10],
            r"field 'group 2': expected disjoint groups, found ID 2",
            id="person-in-two-groups",
        ),
        pytest.param(
            [_gt([1, 2])],
            [15],
            r"GT frame 1 \(GTtimestamp 15\)"
            r": field 'GTtimestamp': expected a value of features.mat's timestamp",
            id="gt-timestamp-not-in-features",
        ),
    ],
)
def test_bad_ground_truth(tmp_path, gt_groups, gt_timestamps, message):
    folder = _write(tmp_path / "gt", gt_groups=gt_groups, gt_timestamps=gt_timestamps)
    assert_refused(load_gcff, folder, message)


# formats.md: each GTgroups entry is a 1×k cell of row vectors of IDs, one per group. A group
# stored as a matrix (two groups written as its rows) is refused, not read as one merged group.
@pytest.mark.parametrize(
    ("entry", "group", "shape"),
    [
        pytest.param(np.array([[1.0, 2.0], [7.0, 3.0]]), 1, "(2, 2)", id="entry-a-matrix"),
        pytest.param(
            _cell([np.array([[1.0, 2.0]]), np.array([[7.0, 3.0], [4.0, 5.0]])]),
            2,
            "(2, 2)",
            id="group-a-matrix",
        ),
        pytest.param(
            _cell([np.array([1.0, 2.0]).reshape(1, 1, 2)]), 1, "(1, 1, 2)", id="group-in-3-d"
        ),
    ],
)
def test_a_group_that_is_not_a_vector_is_refused(tmp_path, entry, group, shape):
    folder = _write(tmp_path / "gt", gt_groups=[entry], gt_timestamps=[10])
    with pytest.raises(DataFormatError) as caught:
        load_gcff(folder)
    assert str(caught.value) == (
        f"{folder / 'groundtruth.mat'}: GT frame 1 (GTtimestamp 10): field 'group {group}': "
        f"expected a row or column vector of IDs (shape (1, k), (k, 1) or (k,)), found shape "
        f"{shape}"
    )


def test_groups_as_rows_or_columns_load_alike(tmp_path):
    column = _cell([np.array([[1.0], [2.0]]), np.array([[7.0]])])
    folder = _write(tmp_path / "col", gt_groups=[column], gt_timestamps=[10])
    assert load_gcff(folder)[0].groups == ((1, 2),)


def test_length_mismatch(tmp_path):
    folder = _write(tmp_path / "len", timestamps=[10, 20])
    assert_refused(
        load_gcff, folder, r"features.mat: field 'timestamp': expected 3 values .*found 2"
    )


def test_complex_numbers_are_refused_not_cast_to_their_real_part(tmp_path):
    # A cast to float would drop the imaginary part with no more than a warning.
    complex_features = [FEATURES[0] + 1j, *FEATURES[1:]]
    assert_refused(
        load_gcff,
        _write(tmp_path / "features", features=complex_features),
        r"features.mat: frame 1: field 'features': expected an N×4 numeric matrix \[ID, x, y, "
        r"θ\], found a complex128 array$",
    )
    features_vars = {
        "features": _cell(FEATURES),
        "timestamp": np.array([TIMESTAMPS], dtype=np.float64) + 7j,
    }
    assert_refused(
        load_gcff,
        _write(tmp_path / "timestamp", features_vars=features_vars),
        r"features.mat: field 'timestamp': expected a numeric vector, found a complex128 array$",
    )
    gt_groups = [_cell([np.array([[1.0, 2.0]]) + 0j]), _gt([1]), _cell([])]
    assert_refused(
        load_gcff,
        _write(tmp_path / "groups", gt_groups=gt_groups, gt_timestamps=TIMESTAMPS),
        r"field 'group 1': expected a numeric vector of IDs, found a complex128 array$",
    )


def test_features_not_a_cell(tmp_path):
    features_vars = {"features": np.zeros((3, 4)), "timestamp": np.array([[1.0]])}
    folder = _write(tmp_path / "nocell", features_vars=features_vars)
    assert_refused(
        load_gcff, folder, r"field 'features': expected a cell array, found a float64 array"
    )


@pytest.mark.parametrize(
    ("timestamps", "message"),
    [
        pytest.param(
            [10, 5, 30],
            r"features.mat: frame 2: field 'timestamp': expected a time > 10.0 \(that of the "
            r"sequence's previous frame, frame 1\): time increases within a sequence, found 5.0",
            id="backwards",
        ),
        pytest.param(
            [10, 20, 20],
            r"features.mat: frame 3: field 'timestamp': expected a time > 20.0 .*found 20.0",
            id="repeated",
        ),
    ],
)
def test_time_must_increase(tmp_path, timestamps, message):
    folder = _write(tmp_path / "t", timestamps=timestamps, gt_timestamps=[10, 20, 30])
    assert_refused(load_gcff, folder, message)


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        pytest.param(
            {"stride": -70.0, "mdl": 10000.0},
            r"settings_gc.mat: field 'stride': expected a finite length >= 0 .*found -70.0",
            id="negative-stride",
        ),
        pytest.param(
            {"stride": 70.0, "mdl": 0.0},
            r"settings_gc.mat: field 'mdl': expected a finite squared length > 0 .*found 0.0",
            id="zero-mdl",
        ),
        pytest.param(
            {"stride": np.nan},
            r"settings_gc.mat: field 'stride': expected a finite length >= 0 .*found nan",
            id="nan-stride",
        ),
    ],
)
def test_bad_folder_settings_are_refused_at_load(tmp_path, settings, message):
    folder = _write(tmp_path / "s", settings=settings)
    assert_refused(load_gcff, folder, message)


# The detector takes a stride of at most 1e8 m and an mdl of at most 1e16 m² (beyond, their
# squares overflow): a settings file beyond is refused as it is read, in its own unit.
@pytest.mark.parametrize(
    ("settings", "units", "message"),
    [
        pytest.param(
            {"stride": 1e12, "mdl": 6000.0},
            "cm",
            "field 'stride': expected a finite length >= 0 and <= 1e+10 file units (1e+08 m, the "
            "most GCFF takes; the o-space centre's distance in front of each person), found "
            "1000000000000.0",
            id="stride-cm",
        ),
        pytest.param(
            {"stride": 5e8, "mdl": 1.0},
            "m",
            "field 'stride': expected a finite length >= 0 and <= 1e+08 file units (1e+08 m, the "
            "most GCFF takes; the o-space centre's distance in front of each person), found "
            "500000000.0",
            id="stride-m",
        ),
        pytest.param(
            {"stride": 70.0, "mdl": 2e20},
            "cm",
            "field 'mdl': expected a finite squared length > 0 and <= 1e+20 file units (1e+16 m², "
            "the most GCFF takes; the cost of opening a group), found 2e+20",
            id="mdl-cm",
        ),
    ],
)
def test_settings_beyond_the_detectors_range_are_refused_naming_the_file(
    tmp_path, settings, units, message
):
    folder = _write(tmp_path / "s", settings=settings)
    expected = f"{folder / 'settings_gc.mat'}: {message}"
    for read in (
        lambda: load_gcff(folder, units=units),
        lambda: read_settings(folder / "settings_gc.mat", units=units),
        lambda: Gcff.from_settings_file(folder / "settings_gc.mat", units=units),
    ):
        with pytest.raises(DataFormatError) as caught:
            read()
        assert str(caught.value) == expected


def test_settings_within_the_detectors_range_load_in_their_unit(tmp_path):
    folder = _write(tmp_path / "s", settings={"stride": 5e8, "mdl": 1.0})  # 5,000 km
    assert load_gcff(folder).metadata["settings_gc"]["stride_m"] == 5e6
    assert read_settings(folder / "settings_gc.mat") == {"stride": 5e8, "mdl": 1.0}


def test_settings_file_that_does_not_exist(tmp_path):
    assert_refused(
        read_settings,
        tmp_path / "nope.mat",
        r"nope.mat: expected a MATLAB .mat file, found no such file",
    )
    assert_refused(read_settings, tmp_path, r"expected a MATLAB .mat file, found a folder")
    scipy.io.savemat(tmp_path / "settings_gc.mat", {"stride": 70.0, "mdl": 10000.0})
    assert read_settings(tmp_path / "settings_gc.mat") == {"stride": 70.0, "mdl": 10000.0}


# Person ids are never negative in the field's formats (formats.md: ID_<digits>, participant
# numbers, GCFF sets numbered from 1): a negative one is refused, named.
@pytest.mark.parametrize(
    ("features", "members", "file", "message"),
    [
        pytest.param(
            [np.array([[1, 100.0, 200.0, 0.5], [-2, 150.0, 200.0, 3.0]])],
            [1, 3],
            "features.mat",
            "frame 1, row 2: field 'ID': expected an integer >= 0 (person ids are never "
            "negative), found -2.0",
            id="person",
        ),
        pytest.param(
            [FEATURES[0]],
            [1, -2],
            "groundtruth.mat",
            "GT frame 1 (GTtimestamp 10): field 'group 1': expected IDs >= 0 (person ids are "
            "never negative), found [1.0, -2.0]",
            id="group-member",
        ),
    ],
)
def test_negative_ids_are_refused(tmp_path, features, members, file, message):
    folder = _write(
        tmp_path / "f",
        features=features,
        timestamps=[10],
        gt_groups=[_gt(members)],
        gt_timestamps=[10],
    )
    with pytest.raises(DataFormatError) as caught:
        load_gcff(folder)
    assert str(caught.value) == f"{folder / file}: {message}"


@pytest.mark.parametrize(
    ("damage", "found"),
    [
        (lambda seq: (seq / "features.mat").unlink(), "groundtruth.mat but no features.mat"),
        (
            lambda seq: (seq / "features.mat").rename(seq / "Features.mat"),
            "Features.mat, groundtruth.mat but no features.mat",
        ),
        (
            lambda seq: (seq / "features.mat").rename(seq / "features.mat.gz"),
            "features.mat.gz, groundtruth.mat but no features.mat",
        ),
        (
            lambda seq: ((seq / "features.mat").unlink(), (seq / "features.mat").mkdir()),
            "features.mat that is a folder",
        ),
        (
            lambda seq: ((seq / "features.mat").unlink(), (seq / "features.mat").symlink_to("x")),
            "features.mat that is a link that leads to no file",
        ),
    ],
    ids=["missing", "renamed", "compressed", "a-folder", "dangling-link"],
)
def test_a_sequence_that_cannot_be_read_is_refused_not_left_out(tmp_path, damage, found):
    folder = tmp_path / "set"
    _write(folder / "Seq1")
    _write(folder / "Seq2")
    damage(folder / "Seq2")
    assert_refused(
        load_gcff,
        folder,
        rf"set/Seq2: expected a GCFF sequence folder like Seq1, with its features.mat, found "
        rf"{re.escape(found)}; put its features file back, or move the folder out",
    )


def test_a_folder_of_settings_alone_is_no_sequence_and_a_folder_of_datasets_says_so(tmp_path):
    folder = tmp_path / "octave"  # as the public repository lays its sets out
    _write(folder / "Synth")
    (folder / "Poster").mkdir()  # its settings only: the data are not public
    scipy.io.savemat(folder / "Poster" / "settings_gc.mat", {"stride": 70.0, "mdl": 10000.0})
    assert [f.sequence for f in load_gcff(folder).frames][:1] == ["Synth"]
    _write(folder / "CoffeeBreak" / "Seq1")
    (folder / "Half").mkdir()
    (folder / "Half" / "groundtruth.mat").write_bytes(b"")  # a sequence without its features
    # Both are wrong: the folder of datasets is what the user meant to name, and is said first.
    assert_refused(load_gcff, folder, r"found a folder of datasets: .*\['CoffeeBreak'\]")
    shutil.rmtree(folder / "CoffeeBreak")
    assert_refused(load_gcff, folder, r"Half: expected a GCFF sequence folder like Synth")


def test_a_folder_of_datasets_is_not_read_as_its_gcff_ones(tmp_path, shared_datasets):
    # The real datasets' folder holds one GCFF sequence (synth) beside other datasets.
    with pytest.raises(DataFormatError) as caught:
        load_gcff(shared_datasets)
    message = str(caught.value)
    assert "found a folder of datasets: GCFF sequences ['synth'] beside other datasets" in message
    assert message.endswith("; name one dataset's folder")
    # A folder of sequences only (CoffeeBreak's layout) still reads, a README beside them.
    _write(tmp_path / "set" / "Seq1")
    _write(tmp_path / "set" / "Seq2")
    (tmp_path / "set" / "README.md").write_text("two sequences\n")
    (tmp_path / "set" / "notes").mkdir()
    assert load_gcff(tmp_path / "set").sequences() == ("Seq1", "Seq2")
    (tmp_path / "set" / "other").mkdir()
    (tmp_path / "set" / "other" / "features.txt").write_text("0.2 ID_001 1 1 0 0\n")
    assert_refused(load_gcff, tmp_path / "set", r"beside other datasets \['other'\]")

"""The SALSA (DANTE text format) loader, on the real files and on malformed copies."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from reform import DataFormatError, wrap_angle
from reform.datasets import load_dataset, load_salsa


@pytest.fixture(scope="session")
def salsa(salsa_dir: Path):
    return load_salsa(salsa_dir)


def _size_table(frames) -> dict[int, int]:
    return dict(sorted(Counter(len(g) for f in frames for g in f.partition()).items()))


# --- the real files (numbers from /work/shared/datasets/salsa/README.md, "verified") ------------


def test_frame_and_session_counts(salsa):
    assert len(salsa) == 1145
    assert salsa.sequences() == ("session1", "session2")
    per_session = Counter(f.sequence for f in salsa)
    assert per_session == {"session1": 645, "session2": 500}
    annotated = Counter(f.sequence for f in salsa.annotated())
    assert annotated == {"session1": 644, "session2": 499}
    # The last frame of each session has no ground truth.
    last = [f for f in salsa if f.sequence == "session1"][-1]
    assert last.groups is None and last.time == 1932.2
    assert salsa[-1].groups is None and salsa[-1].time == 1497.2


def test_every_frame_has_all_18_people_and_times_are_rounded(salsa):
    for frame in salsa:
        assert frame.ids.tolist() == list(range(1, 19))
    times = [f.time for f in salsa if f.sequence == "session2"]
    assert times[:3] == [0.2, 3.2, 6.2]
    assert np.allclose(np.diff(times), 3.0)


def test_canonical_group_size_table(salsa):
    # README table "both, canonical".
    assert _size_table(salsa.annotated()) == {
        1: 1684, 2: 1554, 3: 1705, 4: 952, 5: 539, 6: 381, 7: 238, 8: 25, 12: 1,
    }  # fmt: skip
    s1 = [f for f in salsa.annotated() if f.sequence == "session1"]
    s2 = [f for f in salsa.annotated() if f.sequence == "session2"]
    assert sum(len(f.fformations()) for f in s1) == 2894
    assert sum(len(f.fformations()) for f in s2) == 2501
    assert _size_table(s2)[1] == 1505
    # Frame.groups holds only the F-formations (groups of 2 or more).
    assert all(len(g) >= 2 for f in salsa.annotated() for g in f.groups)


def test_irregularities_are_reported(salsa):
    report = salsa.metadata["report"]
    assert report["missing_from_groundtruth"] == 129
    assert report["groundtruth_lines_with_missing"] == 127
    assert report["duplicate_singletons"] == 3
    assert report["fake_blocks_skipped"] == 0
    assert report["unannotated_feature_lines"] == [645, 1145]


def test_angles_are_wrapped_and_head_is_column_five(salsa):
    for frame in salsa:
        assert np.all(frame.yaw >= -np.pi) and np.all(frame.yaw < np.pi)
        assert np.all(np.abs(frame.head_yaw) <= np.pi)
        np.testing.assert_array_equal(frame.head_position, frame.position)


def test_first_frame_of_session_two_matches_the_readme(salsa):
    # README "Example: one parsed frame (first frame of session 2)".
    frame = next(f for f in salsa if f.sequence == "session2")
    assert frame.time == 0.2
    np.testing.assert_allclose(
        frame.position[:3], [[8.7226, 5.3399], [12.192, 2.1269], [10.098, 1.4242]]
    )
    np.testing.assert_allclose(frame.yaw[:3], [1.92, -2.4, wrap_angle(3.24)])
    np.testing.assert_allclose(frame.head_yaw[:3], [1.52, -2.08, wrap_angle(9.600000000000001)])
    assert frame.yaw[2] == pytest.approx(-3.0432, abs=1e-4)
    assert frame.head_yaw[2] == pytest.approx(-2.9664, abs=1e-4)
    assert frame.groups == ((2, 4), (13, 1), (9, 12, 18, 14, 6), (16, 17), (8, 11, 7, 10, 5))
    assert frame.partition()[-2:] == ((3,), (15,))


def test_load_dataset_detects_salsa(salsa_dir, salsa):
    assert load_dataset(salsa_dir).frames == salsa.frames
    assert load_dataset(salsa_dir, units="m").frames == salsa.frames
    in_cm = load_dataset(salsa_dir, units="cm")  # a unit given is the file's, unchecked
    np.testing.assert_allclose(in_cm.frames[0].position, salsa.frames[0].position / 100)
    assert in_cm.metadata["file_units"] == "cm" and "file_units" not in salsa.metadata
    with pytest.raises(ValueError, match="units='px' needs metres_per_pixel"):
        load_dataset(salsa_dir, units="px")


def test_accepts_the_features_file_path(salsa_dir, salsa):
    dataset = load_salsa(salsa_dir / "features.txt")
    assert dataset.frames == salsa.frames


# --- small synthetic and malformed files -------------------------------------------------------


def _person(i: int, x: float = 1.0, y: float = 2.0, body: float = 0.5, head: float = 0.6) -> str:
    return f"ID_00{i} {x} {y} {body} {head}"


def _write(folder: Path, features: list[str], groups: list[str]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "features.txt").write_text("".join(line + "\n" for line in features))
    (folder / "group_names.txt").write_text("".join(line + "\n" for line in groups))
    return folder


def _copy_head(salsa_dir: Path, folder: Path, n: int = 3) -> tuple[list[str], list[str]]:
    features = (salsa_dir / "features.txt").read_text().splitlines()[:n]
    groups = (salsa_dir / "group_names.txt").read_text().splitlines()[:n]
    return features, groups


def test_fake_blocks_are_skipped(tmp_path):
    features = [f"0.2 {_person(1)} {_person(2, x=3.0)} fake fake fake fake fake"]
    folder = _write(tmp_path, features, ["0.2 < ID_001 ID_002 >"])
    dataset = load_salsa(folder)
    assert dataset[0].ids.tolist() == [1, 2]
    assert dataset.metadata["report"]["fake_blocks_skipped"] == 1
    assert dataset[0].groups == ((1, 2),)


def test_new_session_on_time_decrease_and_gt_matched_by_string(tmp_path):
    features = [f"0.2 {_person(1)}", f"3.2 {_person(1)}", f"0.20002 {_person(1)}"]
    folder = _write(tmp_path, features, ["3.2 < ID_001 >", "0.20002 < ID_001 >"])
    dataset = load_salsa(folder)
    assert [f.sequence for f in dataset] == ["session1", "session1", "session2"]
    assert [f.time for f in dataset] == [0.2, 3.2, 0.2]
    assert [f.annotated for f in dataset] == [False, True, True]


def test_a_session_may_start_earlier_than_the_one_before(tmp_path):
    # Sessions listed out of order (a later recording first) go back past the last one's start.
    times = ["10.0", "13.0", "16.0", "0.0", "3.0"]
    folder = _write(tmp_path, [f"{t} {_person(1)}" for t in times], ["13.0 < ID_001 >"])
    dataset = load_salsa(folder)
    assert [(f.sequence, f.time) for f in dataset] == [
        ("session1", 10.0),
        ("session1", 13.0),
        ("session1", 16.0),
        ("session2", 0.0),
        ("session2", 3.0),
    ]


# Line 2 going back after line 1 alone.
_AFTER_ONE_LINE = (
    r"features.txt: line 2: field 't': expected a time later than line 1's t = {} \(a time "
    r"going back starts a new session only after one of two lines or more; line 1's would hold "
    r"one\), found '{}'$"
)


@pytest.mark.parametrize(
    ("order", "message"),
    [
        pytest.param(
            [7, 6, 5, 4, 3, 2, 1, 0],
            _AFTER_ONE_LINE.format("21.2", "18.2"),
            id="lines-in-reverse-order",
        ),
        pytest.param(
            [1, 0, 2, 3, 4, 5, 6, 7],
            _AFTER_ONE_LINE.format("3.2", "0.2"),
            id="first-two-lines-swapped",
        ),
        pytest.param(
            [0, 1, 2, 3, 5, 4, 6, 7],
            r"features.txt: line 6: field 't': expected a time later than line 5's t = 15.2, "
            r"or, starting a new session, one at most half a frame step \(1.5\) after the start "
            r"of the session before \(line 1's t = 0.2\), found '12.2'$",
            id="two-lines-swapped",
        ),
    ],
)
def test_a_time_going_back_that_is_no_restart(salsa_dir, tmp_path, order, message):
    # SALSA restarts once, after 645 lines (0.2, 3.2, ..., 1932.2, then 0.20002): lines out of
    # order are no such restart, and were read as sessions of a frame or two.
    features, groups = _copy_head(salsa_dir, tmp_path, n=8)
    folder = _write(tmp_path, [features[k] for k in order], [groups[k] for k in order])
    with pytest.raises(DataFormatError, match=message):
        load_salsa(folder)


@pytest.mark.parametrize(
    ("time", "found"),
    [
        pytest.param(None, r"'6.2'", id="line-duplicated"),
        pytest.param("6.20002", r"'6.20002' \(t = 6.2\)", id="same-time-once-rounded"),
    ],
)
def test_repeated_time_within_a_session(salsa_dir, tmp_path, time, found):
    features, groups = _copy_head(salsa_dir, tmp_path, n=5)
    assert features[2].startswith("6.2 ")
    repeated = features[2] if time is None else time + features[2][len("6.2") :]
    features.insert(3, repeated)  # two session1 frames at t = 6.2
    folder = _write(tmp_path, features, groups)
    with pytest.raises(
        DataFormatError,
        match=r"features.txt: line 4: field 't': expected a time > 6.2 \(that of the sequence's "
        r"previous frame, line 3, t = 6.2\): time increases within a sequence, found " + found,
    ):
        load_salsa(folder)


def test_truncated_feature_line(salsa_dir, tmp_path):
    features, groups = _copy_head(salsa_dir, tmp_path)
    features[1] = features[1].rsplit(" ", 3)[0]
    folder = _write(tmp_path, features, groups)
    with pytest.raises(
        DataFormatError, match=r"features.txt: line 2: field 'tokens'.*found 88 tokens"
    ):
        load_salsa(folder)


@pytest.mark.parametrize(
    ("line", "token", "value", "message"),
    [
        pytest.param(3, 9, "inf", r"line 3, person 2: field 'body': .*found 'inf'", id="inf"),
        pytest.param(
            1,
            4,
            "135.0",
            r"line 1, person 1: field 'body': expected an angle in radians.*degrees.*135",
            id="angle-in-degrees",  # person 1's body angle written in degrees
        ),
        pytest.param(
            2,
            2,
            "1e200",
            r"line 2, person 1: field 'x': expected a position with \|value\| <= 1e\+08 m"
            r" \(farther looks like a corrupt value\), found 1e\+200",
            id="huge-position",  # finite, but overflows once squared
        ),
        pytest.param(
            3,
            8,
            "-3e8",
            r"line 3, person 2: field 'y': expected a position .*found -300000000.0",
            id="far-position",
        ),
        # float() reads digits grouped by '_' ('1_2.5' is 12.5): no file of the field writes them.
        pytest.param(
            3,
            2,
            "1_2.5",
            r"features.txt: line 3, person 1: field 'x': expected a number, found '1_2.5'$",
            id="x-digits-grouped-by-underscore",
        ),
        pytest.param(
            2,
            0,
            "3_2",
            r"features.txt: line 2: field 't': expected a number, found '3_2'$",
            id="time-digits-grouped-by-underscore",
        ),
        pytest.param(
            1,
            10,
            "0_0.5",
            r"line 1, person 2: field 'head': expected a number, found '0_0.5'$",
            id="angle-digits-grouped-by-underscore",
        ),
        pytest.param(
            2,
            3,
            "-Infinity",
            r"line 2, person 1: field 'y': expected a finite number, found '-Infinity'$",
            id="infinity-spelled-out",  # a spelling of infinity is refused as infinite, as before
        ),
    ],
)
def test_bad_feature_token(salsa_dir, tmp_path, line, token, value, message):
    features, groups = _copy_head(salsa_dir, tmp_path)
    tokens = features[line - 1].split(" ")
    tokens[token] = value
    features[line - 1] = " ".join(tokens)
    folder = _write(tmp_path, features, groups)
    with pytest.raises(DataFormatError, match=message):
        load_salsa(folder)


@pytest.mark.parametrize(
    ("features", "groups", "message"),
    [
        pytest.param(
            ["0.2 ID_001 1.0 abc 0.1 0.2"],
            ["0.2 < ID_001 >"],
            r"line 1, person 1: field 'y': expected a number, found 'abc'",
            id="non-numeric-token",
        ),
        pytest.param(
            ["0.2 PERSON1 1.0 2.0 0.1 0.2"],
            ["0.2 < ID_001 >"],
            r"line 1: field 'ID': expected a token ID_<number> \(or 'fake'\) after the time, "
            r"found 'PERSON1'",
            id="bad-id-token",
        ),
        pytest.param(
            ["0.2 ID_" + "9" * 40 + " 1.0 2.0 0.1 0.2"],
            ["0.2 < ID_001 >"],
            r"line 1: field 'ID': expected a token ID_<number> with a number <= "
            r"9223372036854775807, found 'ID_9999",
            id="id-beyond-int64",
        ),
        pytest.param(
            [f"0.2 {_person(1)} {_person(1)}"],
            ["0.2 < ID_001 >"],
            r"features.txt: line 1: field 'ID': .*found id 1 twice",
            id="duplicate-ids-in-a-frame",
        ),
        pytest.param(
            [f"0.2 {' '.join(_person(i) for i in (1, 2, 3))}"],
            ["0.2 < ID_001 ID_002 > < ID_002 ID_003 >"],
            r"field 'group 2': expected disjoint groups, found ID 2",
            id="person-in-two-groups",
        ),
    ],
)
def test_bad_small_file(tmp_path, features, groups, message):
    folder = _write(tmp_path, features, groups)
    with pytest.raises(DataFormatError, match=message):
        load_salsa(folder)


@pytest.mark.parametrize("line", [1, 3, 5])
def test_a_bad_id_token_is_named_on_any_line(salsa_dir, tmp_path, line):
    # Line 1 is where the layout (5 fields per person here) is told: a bad ID there was called
    # a truncated line.
    features, groups = _copy_head(salsa_dir, tmp_path, n=5)
    assert " ID_007 " in features[line - 1]
    features[line - 1] = features[line - 1].replace(" ID_007 ", " ID_0O7 ")
    folder = _write(tmp_path, features, groups)
    with pytest.raises(DataFormatError) as caught:
        load_salsa(folder)
    assert str(caught.value) == (
        f"{folder / 'features.txt'}: line {line}: field 'ID': expected a token ID_<number>, "
        "found 'ID_0O7'"
    )


@pytest.mark.parametrize(
    "features",
    [
        pytest.param("0.2 ID_001 1.0 2.0 0.5 ID_0O2 3.0 2.0 0.5", id="4-fields"),
        pytest.param(
            # 21 tokens, 1 + 4 × 5 or 1 + 5 × 4: the IDs that are right tell the layout
            "0.2 ID_001 1.0 2.0 0.5 0.6 ID_0O2 3.0 2.0 0.5 0.6 ID_003 1.0 3.0 0.5 0.6 fake fake "
            "fake fake fake",
            id="5-fields-as-many-tokens-as-4",
        ),
    ],
)
def test_a_bad_id_token_on_the_line_telling_the_layout(tmp_path, features):
    folder = _write(tmp_path, [features], ["0.2 < ID_001 >"])
    with pytest.raises(
        DataFormatError,
        match=r"features.txt: line 1: field 'ID': expected a token ID_<number>, found 'ID_0O2'$",
    ):
        load_salsa(folder)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        pytest.param(
            lambda line: line[: line.rindex(">")].rstrip(),
            r"group_names.txt: line 2: field 'groups': expected '>' closing",
            id="truncated-group-line",
        ),
        pytest.param(
            lambda line: "7.7" + line[line.index(" ") :],
            r"group_names.txt: line 2: field 'time': .*found '7.7'",
            id="group-time-matching-no-feature-line",
        ),
    ],
)
def test_an_edited_group_line_is_refused(salsa_dir, tmp_path, edit, message):
    features, groups = _copy_head(salsa_dir, tmp_path)
    groups[1] = edit(groups[1])
    folder = _write(tmp_path, features, groups)
    with pytest.raises(DataFormatError, match=message):
        load_salsa(folder)


def test_empty_and_missing_files(salsa_dir, tmp_path):
    features, groups = _copy_head(salsa_dir, tmp_path)
    folder = _write(tmp_path / "empty", features, groups)
    (folder / "features.txt").write_text("")
    with pytest.raises(
        DataFormatError,
        match=r"features.txt: expected a DANTE features file \(a non-empty file\), found an empty",
    ):
        load_salsa(folder)
    folder = _write(tmp_path / "missing", features, groups)
    (folder / "group_names.txt").unlink()
    with pytest.raises(
        DataFormatError, match=r"group_names.txt: expected a DANTE group file.*found no such file"
    ):
        load_salsa(folder)
    with pytest.raises(DataFormatError, match="no such file"):
        load_dataset(tmp_path / "nowhere", format="salsa")


def test_empty_line_in_features(salsa_dir, tmp_path):
    features, groups = _copy_head(salsa_dir, tmp_path)
    features.insert(1, "")
    folder = _write(tmp_path, features, groups)
    with pytest.raises(
        DataFormatError, match=r"features.txt: line 2: expected .*found an empty line"
    ):
        load_salsa(folder)

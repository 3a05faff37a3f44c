"""The Babble loader, on the real files and on malformed copies."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from dataset_refusals import assert_refused

from reform.datasets import load_babble, load_dataset


@pytest.fixture(scope="session")
def babble(babble_dir: Path):
    return load_babble(babble_dir)


def _frame(dataset, number: int):
    return dataset[dataset.metadata["frame_numbers"].index(number)]


# --- the real files (numbers from /work/shared/datasets/babble/README.md, "verified") -----------


def test_every_row_is_a_frame_and_99_are_annotated(babble):
    assert len(babble) == 3481
    assert babble.sequences() == ("babble",)
    assert len(babble.annotated()) == 99
    report = babble.metadata["report"]
    assert report["rows"] == 3481
    assert report["annotated_frames"] == 99
    assert report["annotation_lines_duplicated"] == 1  # frame 2840, listed twice identically


def test_time_comes_from_the_vicon_counter(babble):
    # FrameNum runs 283148 -> 479627 at 100 Hz (README); the wall clock spans 1,965 s.
    assert babble[0].time == 0.0
    assert babble[-1].time == pytest.approx(1964.79)
    assert np.all(np.diff([f.time for f in babble]) > 0)
    assert babble.metadata["report"]["max_clock_gap_s"] < 1.5


def test_group_sizes_of_the_annotated_frames(babble):
    # README: over the 100 lines 7x23, 6x15, 5x20, 4x10, 3x19, 2x8, empty x5; one 3-group line is
    # the duplicate of frame 2840.
    sizes = Counter(len(g) for f in babble.annotated() for g in f.fformations())
    assert sizes == {7: 23, 6: 15, 5: 20, 4: 10, 3: 18, 2: 8}
    empty = [n for n in babble.metadata["frame_numbers"] if _frame(babble, n).groups == ()]
    assert empty == [404, 570, 1125, 1481, 2752]
    assert _frame(babble, 2840).groups == ((3, 4, 7),)


def test_leavers(babble):
    # README: participants leave in the order 1 (721/740), 6 (1448/1523), 2 (2002/2019),
    # 5 (2401/2637), 3 (3081/3113): last annotated frame in the group / first without them.
    for person, last, first_without in [
        (1, 721, 740),
        (6, 1448, 1523),
        (2, 2002, 2019),
        (5, 2401, 2637),
        (3, 3081, 3113),
    ]:
        assert person in _frame(babble, last).groups[0]
        assert all(person not in g for g in _frame(babble, first_without).groups)


def test_untracked_torsos_and_heads(babble):
    # Participant 7's torso is always tracked, participant 1's in 754 of 3,481 frames (README:
    # 2,727 untracked).
    present = Counter(int(i) for f in babble for i in f.ids)
    assert present[7] == 3481
    assert present[1] == 3481 - 2727
    # Untracked head -> NaN head, never a (0, 0) head.
    for frame in babble:
        finite = ~np.isnan(frame.head_yaw)
        assert not np.any(np.all(frame.head_position[finite] == 0.0, axis=1))


def test_annotated_members_without_torso_use_their_head(babble):
    assert babble.metadata["report"]["torso_from_head"] == [[79, 6], [520, 4], [721, 3]]
    assert babble.metadata["report"]["members_dropped"] == []
    frame = _frame(babble, 520)
    i = frame.index_of(4)
    np.testing.assert_array_equal(frame.position[i], frame.head_position[i])
    assert 4 in frame.groups[0]
    assert frame.groups[0] == (1, 2, 3, 4, 5, 6, 7)


def test_swapped_heads_of_participants_3_and_4(babble):
    report = babble.metadata["report"]
    # README: full swaps in 107 frames; block 3 holds 4's head while 4's is missing in 53, and
    # the reverse in 43 by the same rule (README's count of 44 includes one frame where block 4's
    # head is not within 0.5 m of torso 3).
    assert report["heads_swapped_back"] == 107
    assert report["heads_moved"] == 53 + 43
    assert report["misplaced_heads_by_owner"] == {"3->4": 160, "4->3": 150}
    assert report["heads_dropped_duplicate"] == 1  # frame 1285: block 3 repeats 4's head
    assert report["heads_dropped_far"] == 3  # 2 of participant 4, 1 of participant 6
    # Frame 1 is a full swap: block 3's head (-1.711, -0.608) sits on torso 4, block 4's on torso 3.
    frame = babble[0]
    np.testing.assert_allclose(frame.head_position[frame.index_of(4)], [-1.711, -0.608])
    np.testing.assert_allclose(frame.head_position[frame.index_of(3)], [-0.404, -0.686])
    # After the repair every observed head is within 0.5 m of its body.
    for frame in babble:
        gap = np.hypot(*(frame.head_position - frame.position).T)
        assert np.all(gap[~np.isnan(gap)] <= 0.5)


def test_annotated_only(babble_dir, babble):
    subset = load_babble(babble_dir, annotated_only=True)
    assert len(subset) == 99
    assert subset.frames == babble.annotated()
    assert subset.metadata["frame_numbers"][:3] == [16, 73, 79]


def test_load_dataset_detects_babble(babble_dir):
    dataset = load_dataset(babble_dir, units="m")
    assert dataset.name == "babble"
    with pytest.raises(ValueError, match="babble format stores positions in 'm', got units='cm'"):
        load_dataset(babble_dir, units="cm")


# --- malformed copies --------------------------------------------------------------------------


def _copy(babble_dir: Path, folder: Path, *, rows: int = 20, annotations: list[str] | None = None):
    folder.mkdir(parents=True, exist_ok=True)
    lines = (babble_dir / "Motion-capture-data.csv").read_text().splitlines()[: rows + 1]
    if annotations is None:
        annotations = ["16,{[1 2 3 4 5 6 7]}", "18,{[]}"]
    return folder, lines, annotations


def _write(folder: Path, lines: list[str], annotations: list[str]) -> Path:
    (folder / "Motion-capture-data.csv").write_text("".join(line + "\n" for line in lines))
    (folder / "annotated-frames.csv").write_text("".join(line + "\n" for line in annotations))
    return folder


def _set_field(lines: list[str], line: int, field: int, value: str) -> None:
    fields = lines[line - 1].split(",")
    fields[field] = value
    lines[line - 1] = ",".join(fields)


def test_small_copy_loads(babble_dir, tmp_path):
    folder = _write(*_copy(babble_dir, tmp_path))
    dataset = load_babble(folder)
    assert len(dataset) == 20
    assert [f.annotated for f in dataset].count(True) == 2


def test_truncated_line(babble_dir, tmp_path):
    folder, lines, annotations = _copy(babble_dir, tmp_path)
    lines[5] = lines[5][: lines[5].index(",6,")]
    _write(folder, lines, annotations)
    assert_refused(
        load_babble,
        folder,
        r"Motion-capture-data.csv: line 6 \(frame 5\)"
        r": field 'fields': expected 70 .*found 50 fields",
    )


@pytest.mark.parametrize(
    ("line", "field", "value", "message"),
    [
        pytest.param(
            4,
            14,
            "NaN",
            r"line 4 \(frame 3\), participant 2"
            r": field 'TorsoX': expected a finite number, found 'NaN'",
            id="nan-value",  # participant 2, TorsoX
        ),
        pytest.param(
            3,
            6,
            "-5.0",
            r"line 3 \(frame 2\), participant 1"
            r": field 'TorsoRotation': expected an angle in radians.*degrees.*-5.0",
            id="angle-in-degrees",  # participant 1, TorsoRotation written in degrees
        ),
        pytest.param(
            2,
            10,
            "1",
            r"line 2 \(frame 1\): field 'Name': .*found id 1 twice",
            id="duplicate-participant",  # block 2 named participant 1
        ),
        pytest.param(
            3,
            9,
            "xx:yy",
            r"line 3 \(frame 2\), participant 1"
            r": field 'Time': expected a time like H:MM:SS, found 'xx:yy'",
            id="bad-time-of-the-first-participant",
        ),
        pytest.param(
            3,
            19,
            "5:48:51",
            r"line 3 \(frame 2\), participant 2"
            r": field 'Time': expected the line's Time, 5:48:50 \(participant 1\), found '5:48:51'",
            id="time-differs-between-participants",
        ),
        pytest.param(
            3,
            8,
            "283206.5",
            r"line 3 \(frame 2\), participant 1"
            r": field 'FrameNum': expected an integer Vicon frame number, found '283206.5'",
            id="fractional-frame-number",
        ),
        pytest.param(
            3,
            14,
            "1e200",
            r"line 3 \(frame 2\), participant 2"
            r": field 'TorsoX': expected a position with \|value\| <= 1e\+08 m.*found 1e\+200",
            id="huge-position",
        ),
        # float() reads digits grouped by '_' ('-1_1.35' is -11.35): Babble writes none.
        pytest.param(
            4,
            14,
            "-1_1.35",
            r"line 4 \(frame 3\), participant 2"
            r": field 'TorsoX': expected a number, found '-1_1.35'$",
            id="digits-grouped-by-underscore",
        ),
        pytest.param(
            3,
            8,
            "283_206",
            r"line 3 \(frame 2\), participant 1"
            r": field 'FrameNum': expected a number, found '283_206'$",
            id="frame-number-grouped-by-underscore",
        ),
        pytest.param(
            4,
            17,
            "tall",
            r"line 4 \(frame 3\), participant 2: field 'Hieght': expected a number, found 'tall'$",
            id="height-not-a-number",  # Hieght (sic) is read by no detector, but is a number
        ),
        pytest.param(
            2,
            10,
            "9" * 23,
            r"line 2 \(frame 1\): field 'Name \(block 2\)': expected a participant number <= "
            r"9223372036854775807, found 9{23} \(23 digits\)$",
            id="participant-beyond-int64",  # was an OverflowError
        ),
    ],
)
def test_bad_motion_field(babble_dir, tmp_path, line, field, value, message):
    folder, lines, annotations = _copy(babble_dir, tmp_path)
    _set_field(lines, line, field, value)
    _write(folder, lines, annotations)
    assert_refused(load_babble, folder, message)


def test_positions_in_millimetres_are_refused_not_read_as_metres(babble_dir, tmp_path):
    folder, lines, annotations = _copy(babble_dir, tmp_path)
    for k in range(1, len(lines)):
        fields = lines[k].split(",")
        for block in range(7):
            for field in (1, 2, 4, 5):  # head x, y; torso x, y
                at = 10 * block + field
                fields[at] = f"{1000 * float(fields[at]):.3f}"
        lines[k] = ",".join(fields)
    _write(folder, lines, annotations)
    assert_refused(
        load_babble,
        folder,
        r"Motion-capture-data.csv: field 'positions': expected metres, people a median of at most "
        r"20 m .*; the format holds metres: convert the positions to metres",
    )


def test_repeated_frame_number(babble_dir, tmp_path):
    folder, lines, annotations = _copy(babble_dir, tmp_path)
    previous = lines[2].split(",")[8]
    for block in range(7):  # every participant of line 4 carries line 3's FrameNum
        _set_field(lines, 4, 10 * block + 8, previous)
    _write(folder, lines, annotations)
    assert_refused(
        load_babble,
        folder,
        r"line 4 \(frame 3\): field 'FrameNum': expected a Vicon frame number above "
        rf"{previous} \(line 3\): time increases, found {previous}",
    )


def _set_every_block(lines: list[str], line: int, field: int, value: str) -> None:
    for block in range(7):
        _set_field(lines, line, 10 * block + field, value)


# Lines 9 and 10 of the real file: FrameNum 283546 and 283602 (0.56 s at 100 Hz), Time 5:48:53
# and 5:48:54.


def test_a_frame_number_jump_that_time_contradicts(babble_dir, tmp_path):
    folder, lines, annotations = _copy(babble_dir, tmp_path)
    for line in range(10, len(lines) + 1):  # FrameNum + 1e9 from line 10 on: 1e7 s, says FrameNum
        _set_every_block(lines, line, 8, str(int(lines[line - 1].split(",")[8]) + 10**9))
    _write(folder, lines, annotations)
    assert_refused(
        load_babble,
        folder,
        r"Motion-capture-data.csv: line 10 \(frame 9\): field 'FrameNum': expected a step that "
        r"agrees with Time's within 2 s at 100 Hz \(Time goes from 5:48:53 on line 9 to 5:48:54: "
        r"1 s\), found 1000283602 after 283546 \(line 9\): 10000000.56 s$",
    )


def test_a_time_going_back_that_is_no_wrap(babble_dir, tmp_path):
    folder, lines, annotations = _copy(babble_dir, tmp_path)
    _set_every_block(lines, 10, 9, "5:48:44")  # 9 s back, not 12 h
    _write(folder, lines, annotations)
    assert_refused(
        load_babble,
        folder,
        r"Motion-capture-data.csv: line 10 \(frame 9\): field 'Time': expected a Time from "
        r"5:48:53 \(line 9\) on, 0.56 s later as FrameNum steps \(within 2 s\), or the 12-hour "
        r"clock's wrap from 12:59:59 to 1:00:00, found '5:48:44'$",
    )


@pytest.mark.parametrize(
    ("first", "clock"),
    [
        pytest.param("12:59:55", 12, id="12-hour-clock"),  # 12:59:59 -> 1:00:00, as Babble's
        pytest.param("11:59:55", 0, id="12-hour-clock-from-0"),  # 11:59:59 -> 0:00:00
        pytest.param("23:59:55", 24, id="24-hour-clock"),  # 23:59:59 -> 0:00:00
    ],
)
def test_the_clock_wrapping_around_loads_as_before(babble_dir, tmp_path, first, clock):
    folder, lines, annotations = _copy(babble_dir, tmp_path / "as-recorded")
    before = load_babble(_write(folder, lines, annotations))
    hours, minutes, seconds = (int(n) for n in first.split(":"))
    shift = hours * 3600 + minutes * 60 + seconds - (5 * 3600 + 48 * 60 + 49)  # line 2: 5:48:49
    for line in range(2, len(lines) + 1):
        h, m, s = (int(n) for n in lines[line - 1].split(",")[9].split(":"))
        h, rest = divmod(h * 3600 + m * 60 + s + shift, 3600)
        h %= 24 if clock == 24 else 12
        h = 12 if clock == 12 and h == 0 else h
        _set_every_block(lines, line, 9, f"{h}:{rest // 60:02d}:{rest % 60:02d}")
    stamps = [tuple(int(n) for n in line.split(",")[9].split(":")) for line in lines[1:]]
    assert stamps != sorted(stamps)  # the clock wraps
    (tmp_path / "wrapped").mkdir()
    wrapped = load_babble(_write(tmp_path / "wrapped", lines, annotations))
    assert wrapped.frames == before.frames
    assert wrapped.metadata["report"] == before.metadata["report"]


def test_identical_duplicate_annotation_is_counted(babble_dir, tmp_path):
    folder, lines, _ = _copy(babble_dir, tmp_path)
    _write(folder, lines, ["16,{[1 2 3]}", "16,{[1 2 3]}"])
    assert load_babble(folder).metadata["report"]["annotation_lines_duplicated"] == 1


@pytest.mark.parametrize(
    ("annotations", "message"),
    [
        pytest.param(
            ["16,{[1 2 3]}", "16,{[1 2]}"],
            r"annotated-frames.csv: line 2 \(frame 16\)"
            r": field 'groups': expected the groups of line 1",
            id="conflicting-duplicate",
        ),
        pytest.param(
            ["16,{[1 2 9]}"],
            r"line 1 \(frame 16\): field 'group 1': expected members present .*found participant 9",
            id="group-member-absent",
        ),
        pytest.param(
            ["16,{[1 2]}", "999,{[1 2]}"],
            r"line 2 \(frame 999\): field 'frame': expected a frame number in 1..20",
            id="frame-beyond-the-recording",
        ),
        pytest.param(
            ["16,{[1 2 3"],
            r"annotated-frames.csv: line 1: expected N,\{\[id id",
            id="malformed-line",
        ),
        pytest.param(
            ["1" * 5000 + ",{[1 2]}"],
            r"annotated-frames.csv: line 1: field 'frame': expected a frame number <= "
            r"9223372036854775807, found 1{100}… \([\d,]+ characters\)$",
            id="frame-of-5000-digits",  # Python reads at most 4,300 digits
        ),
        pytest.param(
            ["16,{[1 " + "2" * 5000 + "]}"],
            r"line 1 \(frame 16\): field 'group 1': expected a participant number <= "
            r"9223372036854775807, found 2{100}… \([\d,]+ characters\)$",
            id="member-of-5000-digits",
        ),
    ],
)
def test_bad_annotations(babble_dir, tmp_path, annotations, message):
    folder, lines, _ = _copy(babble_dir, tmp_path)
    _write(folder, lines, annotations)
    assert_refused(load_babble, folder, message)


def test_empty_and_missing_files(babble_dir, tmp_path):
    folder = _write(*_copy(babble_dir, tmp_path / "a"))
    (folder / "annotated-frames.csv").write_text("")
    assert_refused(load_babble, folder, r"annotated-frames.csv: expected .*found an empty file")
    folder = _write(*_copy(babble_dir, tmp_path / "b"))
    (folder / "annotated-frames.csv").unlink()
    assert_refused(load_babble, folder, r"annotated-frames.csv: expected .*found no such file")
    folder = _write(*_copy(babble_dir, tmp_path / "c", rows=0))
    assert_refused(load_babble, folder, r"Motion-capture-data.csv: expected at least one data line")


def test_an_annotated_member_tracked_nowhere_stays_in_the_ground_truth(babble_dir, tmp_path):
    folder, lines, annotations = _copy(babble_dir, tmp_path)
    for field in range(41, 48):  # participant 5 of frame 16 (line 17): head, torso, height
        _set_field(lines, 17, field, "0")
    dataset = load_babble(_write(folder, lines, annotations))
    frame = dataset.frames[15]
    assert 5 not in frame.ids.tolist()
    assert frame.groups == ((1, 2, 3, 4, 6, 7),)
    assert frame.listed_groups == ((1, 2, 3, 4, 5, 6, 7),)  # missed, as ff_evalgroups counts it
    assert dataset.metadata["report"]["members_dropped"] == [[16, 5]]

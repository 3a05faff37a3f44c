"""The field's files as they are: quirks loaded faithfully, counted, and refused only by strict.

Ground truth naming someone absent from the features, NaN poses, DANTE's two layouts, pixel
units and folders of sequences, in small files written here; the real CoffeeBreak at the end.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io

from reform import DataFormatError, Frame
from reform.datasets import detect_format, load_dante, load_dataset, load_gcff
from reform.datasets.summary import repairs_line
from reform.metrics import evaluate


def _cell(items) -> np.ndarray:
    array = np.empty((1, len(items)), dtype=object)
    for k, item in enumerate(items):
        array[0, k] = item
    return array


def _gcff(folder: Path, features, groups, *, settings=None) -> Path:
    """A GCFF folder: one frame per ``features`` entry (timestamps 1, 2, ...), all annotated."""
    folder.mkdir(parents=True, exist_ok=True)
    stamps = np.arange(1, len(features) + 1, dtype=np.float64)[None, :]
    scipy.io.savemat(
        folder / "features.mat",
        {
            "features": _cell([np.asarray(f, dtype=np.float64) for f in features]),
            "timestamp": stamps,
        },
    )
    gt = _cell([_cell([np.array([g], dtype=np.float64) for g in frame]) for frame in groups])
    scipy.io.savemat(folder / "groundtruth.mat", {"GTgroups": gt, "GTtimestamp": stamps})
    if settings is not None:
        scipy.io.savemat(folder / "settings_gc.mat", settings)
    return folder


# Three people in centimetres; the annotators also saw person 42, whom the tracker lost.
PEOPLE = [[1, 100.0, 0.0, np.pi], [2, 0.0, 0.0, 0.0], [3, 500.0, 500.0, 0.0]]


@pytest.mark.parametrize(("offset", "matched"), [(1e-6, True), (1.2, False)])
def test_ground_truth_times_match_a_frame_not_its_neighbourhood(tmp_path, offset, matched):
    """Unix times 5 s apart (Cocktail Party's): a ground-truth time a rounding away from a frame's
    is that frame's; 1.2 s away is no frame's, though a relative tolerance alone spans 1.3 s."""
    stamps = 1275403283.267134 + 5.0 * np.arange(3)
    people = np.array([p[:3] + [0.0] for p in PEOPLE])
    scipy.io.savemat(
        tmp_path / "features.mat",
        {"features": _cell([people[:, :4]] * 3), "timestamp": stamps[None, :]},
    )
    gt = _cell([_cell([np.array([[1.0, 2.0]])])])
    stamp = stamps[1] + offset
    scipy.io.savemat(
        tmp_path / "groundtruth.mat", {"GTgroups": gt, "GTtimestamp": np.array([[stamp]])}
    )
    if matched:
        frames = load_gcff(tmp_path).frames
        assert [f.groups for f in frames] == [None, ((1, 2),), None]
        return
    with pytest.raises(DataFormatError, match="expected a value of features.mat's timestamp"):
        load_gcff(tmp_path)


# --- ground truth naming people absent from the features ---------------------------------------


def test_absent_ground_truth_member_stays_in_the_ground_truth(tmp_path):
    folder = _gcff(tmp_path / "set", [PEOPLE], [[[1, 2, 42]]])
    dataset = load_gcff(folder)
    (frame,) = dataset.frames
    assert frame.groups == ((1, 2),)  # what detectors and training see
    assert frame.listed_groups == ((1, 2, 42),)  # what the evaluation scores against
    assert frame.unseen_members == (42,)
    report = dataset.metadata["report"]
    assert report["repairs"] == {"groundtruth_members_absent": 1}
    assert report["groundtruth_frames_with_absent_members"] == 1
    assert "field 'group 1'" in report["first_repair"]["groundtruth_members_absent"]


def test_an_absent_member_counts_as_missed_as_ff_evalgroups_counts_it(tmp_path):
    # True {1, 2, 42} against detected {1, 2}: 2 of max(3, 2) = 2/3 matches at T = 2/3 and
    # misses at T = 1 (formats.md, the GCFF evaluation code's rule).
    (frame,) = load_gcff(_gcff(tmp_path / "set", [PEOPLE], [[[1, 2, 42]]])).frames
    scores = evaluate([frame], [((1, 2), (3,))])
    assert (scores.at("2/3").precision, scores.at("2/3").recall) == (1.0, 1.0)
    assert (scores.at("1").precision, scores.at("1").recall) == (0.0, 0.0)
    assert scores.pairwise_accuracy == 1.0  # pairs are the frame's people's only


def test_a_group_with_nobody_present_is_a_true_group_missed(tmp_path):
    (frame,) = load_gcff(_gcff(tmp_path / "set", [PEOPLE], [[[1, 2], [41, 42]]])).frames
    assert frame.groups == ((1, 2),)
    assert frame.listed_groups == ((1, 2), (41, 42))
    scores = evaluate([frame], [((1, 2), (3,))])
    assert scores.at("2/3").micro.tp == 1 and scores.at("2/3").micro.fn == 1


def test_an_absent_singleton_is_accepted(tmp_path):
    (frame,) = load_gcff(_gcff(tmp_path / "set", [PEOPLE], [[[1, 2], [42]]])).frames
    assert frame.groups == ((1, 2),) and frame.listed_groups is None


def test_strict_refuses_an_absent_member(tmp_path):
    folder = _gcff(tmp_path / "set", [PEOPLE], [[[1, 2, 42]]])
    with pytest.raises(
        DataFormatError,
        match=r"groundtruth.mat: GT frame 1 \(GTtimestamp 1\): field 'group 1': expected members "
        r"present in the frame's features \(IDs \[1, 2, 3\]\).*found ID 42; refused by --strict",
    ):
        load_dataset(folder, strict=True)


def test_listed_groups_must_agree_with_groups():
    with pytest.raises(ValueError, match=r"members present in the frame must be groups'"):
        Frame(
            ids=[1, 2, 3],
            position=np.zeros((3, 2)),
            yaw=np.zeros(3),
            groups=((1, 3),),
            listed_groups=((1, 2, 42),),
        )
    with pytest.raises(ValueError, match=r"listed_groups needs groups"):
        Frame(ids=[1], position=np.zeros((1, 2)), yaw=np.zeros(1), listed_groups=((1, 42),))


# --- NaN poses ----------------------------------------------------------------------------------


def test_a_nan_pose_is_dropped_from_its_frame(tmp_path):
    people = [*PEOPLE, [4, np.nan, np.nan, np.nan]]
    dataset = load_gcff(_gcff(tmp_path / "set", [people], [[[1, 2], [3, 4]]]))
    (frame,) = dataset.frames
    assert frame.ids.tolist() == [1, 2, 3]
    assert frame.listed_groups == ((1, 2), (3, 4))  # 4 was annotated: an absent member now
    assert dataset.metadata["report"]["repairs"] == {
        "people_dropped_nan": 1,
        "groundtruth_members_absent": 1,
    }
    with pytest.raises(
        DataFormatError,
        match=r"features.mat: frame 1, row 4 \(ID 4\): field 'x': expected a number \(a NaN pose: "
        r"that person is dropped from the frame\), found NaN; refused by --strict",
    ):
        load_gcff(tmp_path / "set", strict=True)


def test_nan_poses_in_assumed_centimetres_are_said_to_mark_image_pixels(tmp_path):
    # NaN poses are the mark of sets derived from pose estimation, whose positions are pixels:
    # read in the centimetres assumed, the note says so and how to give the unit.
    folder = _gcff(tmp_path / "set", [[*PEOPLE, [4, np.nan, 0.0, 0.0]]], [[[1, 2]]])
    assumed = load_gcff(folder)
    line = repairs_line(assumed, "set")
    assert line.endswith(
        "positions read in centimetres, the unit assumed when none is given, though 1 poses are "
        "NaN, the mark of a set derived from pose estimation, whose positions are image pixels: "
        "give units='px' with metres_per_pixel (--units px --metres-per-pixel M) if they are "
        "pixels, units='cm' (--units cm) to say they are centimetres"
    )
    stated = load_gcff(folder, units="cm")
    assert "units_caution" not in stated.metadata["report"]
    assert "pixels" not in repairs_line(stated, "set")
    clean = load_gcff(_gcff(tmp_path / "clean", [PEOPLE], [[[1, 2]]]))
    assert "units_caution" not in clean.metadata["report"]


def test_a_nan_id_is_malformed(tmp_path):
    folder = _gcff(tmp_path / "set", [[*PEOPLE, [np.nan, 1.0, 1.0, 0.0]]], [[[1, 2]]])
    with pytest.raises(
        DataFormatError, match=r"frame 1, row 4: field 'ID': expected a finite number, found nan$"
    ):
        load_gcff(folder)


# --- pixels -------------------------------------------------------------------------------------


def test_pixels_load_only_with_their_scale(tmp_path):
    folder = _gcff(tmp_path / "px", [PEOPLE], [[[1, 2]]], settings={"stride": 40.0, "mdl": 900.0})
    with pytest.raises(ValueError, match=r"units='px' needs metres_per_pixel"):
        load_dataset(folder, units="px")
    with pytest.raises(ValueError, match=r"metres_per_pixel must be a positive number, got -1"):
        load_dataset(folder, units="px", metres_per_pixel=-1)
    with pytest.raises(ValueError, match=r"metres_per_pixel is the scale of units='px'"):
        load_dataset(folder, metres_per_pixel=0.01)
    dataset = load_dataset(folder, units="px", metres_per_pixel=0.005)
    np.testing.assert_allclose(dataset.frames[0].position[0], [0.5, 0.0])
    settings = dataset.metadata["settings_gc"]
    assert (settings["stride_m"], settings["mdl_m2"]) == pytest.approx((0.2, 900 * 0.005**2))
    assert dataset.metadata["metres_per_pixel"] == 0.005


# --- a folder of sequences -----------------------------------------------------------------------


def test_a_folder_of_gcff_folders_is_one_dataset_a_sequence_each(tmp_path):
    root = tmp_path / "GDet"
    _gcff(root / "S2", [PEOPLE], [[[1, 2]]], settings={"stride": 30.0, "mdl": 5000.0})
    _gcff(
        root / "S1", [PEOPLE, PEOPLE], [[[1, 2]], [[2, 3]]], settings={"stride": 50.0, "mdl": 9e3}
    )
    (root / "notes").mkdir()  # a folder without features.mat is not a sequence
    assert detect_format(root) == "gcff"
    dataset = load_dataset(root)
    assert dataset.name == "GDet"
    assert [f.sequence for f in dataset] == ["S1", "S1", "S2"]
    by_sequence = dataset.metadata["settings_gc_by_sequence"]
    assert {name: s["stride_m"] for name, s in by_sequence.items()} == {"S1": 0.5, "S2": 0.3}
    assert "settings_gc" not in dataset.metadata  # no single setting for the whole dataset
    report = dataset.metadata["report"]
    assert report["frames"] == 3 and report["by_sequence"]["S1"]["annotated_frames"] == 2


def test_a_folder_with_no_gcff_folder_is_refused(tmp_path):
    (tmp_path / "empty" / "sub").mkdir(parents=True)
    with pytest.raises(DataFormatError, match=r"empty: expected a GCFF folder .* or a folder of"):
        load_gcff(tmp_path / "empty")


def test_real_coffeebreak_root_holds_both_sequences(shared_datasets):
    dataset = load_dataset(shared_datasets / "coffeebreak")
    assert dataset.sequences() == ("Seq1", "Seq2")
    # coffeebreak/README.md: 45 annotated frames in Seq1, 74 in Seq2; 50/8000 and 20/7000.
    assert dataset.metadata["report"]["annotated_frames"] == 45 + 74
    settings = dataset.metadata["settings_gc_by_sequence"]
    assert [(s["stride"], s["mdl"]) for s in settings.values()] == [(50, 8000), (20, 7000)]


# --- DANTE text: 4 or 5 fields per person --------------------------------------------------------


def _dante(folder: Path, features: list[str], groups: list[str]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "features.txt").write_text("".join(line + "\n" for line in features))
    (folder / "group_names.txt").write_text("".join(line + " \n" for line in groups))
    return folder


def test_dante_with_four_fields_per_person(tmp_path):
    folder = _dante(
        tmp_path / "cocktail",
        [
            "1275403283.267134 ID_001 3.73 2.24 6.102 ID_002 2.19 4.31 0.480 ID_0010 3.0 3.0 1.0",
            "1275403288.272120 ID_001 3.53 2.07 0.668 fake fake fake fake ID_0010 3.1 3.0 1.0",
        ],
        [
            "1275403283.267134 < ID_001 ID_002 > < ID_0010 >",
            "1275403288.272120 < ID_001 ID_0010 >",
        ],
    )
    dataset = load_dante(folder)
    first, second = dataset.frames
    assert dataset.name == "cocktail"
    assert dataset.metadata["fields_per_person"] == 4
    assert first.ids.tolist() == [1, 2, 10] and second.ids.tolist() == [1, 10]
    assert first.head_yaw is None  # one orientation per person
    np.testing.assert_allclose(first.yaw[0], 6.102 - 2 * np.pi)
    assert first.groups == ((1, 2),) and second.groups == ((1, 10),)
    # Unix seconds (Cocktail Party's): counted from the session's first line, the origin kept.
    assert first.time == 0.0
    assert second.time == pytest.approx(1275403288.272120 - 1275403283.267134, abs=1e-6)
    assert dataset.metadata["report"]["time_unit"]["origin_unix_s"] == {
        "session1": 1275403283.267134
    }
    assert dataset.metadata["report"]["fake_blocks_skipped"] == 1


def test_dantes_own_layout_is_named_after_the_dataset_not_ds_utils(tmp_path):
    # DANTE's repository: datasets/<dataset>/DS_utils/{features,group_names}.txt
    lines = (["0.0 ID_001 1.0 1.0 0.0 ID_002 2.0 1.0 3.1"], ["0.0 < ID_001 ID_002 >"])
    folder = _dante(tmp_path / "cocktail_party" / "DS_utils", *lines)
    assert load_dante(folder).name == "cocktail_party"
    assert load_dante(folder / "features.txt").name == "cocktail_party"
    assert load_dataset(folder).name == "cocktail_party"
    assert load_dante(_dante(tmp_path / "utils", *lines)).name == "utils"
    # The dataset's own folder, as a clone of the repository has it, is found and read too.
    dataset = tmp_path / "cocktail_party"
    assert detect_format(dataset) == "salsa"
    assert load_dataset(dataset).name == "cocktail_party"
    assert load_dante(dataset).frames == load_dante(folder).frames


def _dante_in_cm(folder: Path) -> Path:
    """Two lines as DANTE's CoffeeBreak text files write them: centimetres, not metres."""
    return _dante(
        folder,
        [
            "1 ID_001 1.767008e+02 1.357453e+02 1.570796e+00 ID_002 2.46e+02 1.40e+02 3.14 "
            "fake fake fake fake",
            "13 ID_001 1.77e+02 1.36e+02 1.57 ID_002 2.47e+02 1.41e+02 3.14 ID_003 9.0e+02 "
            "8.0e+02 0.0",
        ],
        ["1 < ID_001 ID_002 >", "13 < ID_001 ID_002 > < ID_003 >"],
    )


def test_dante_in_centimetres_is_refused_unless_the_unit_is_given(tmp_path):
    folder = _dante_in_cm(tmp_path / "coffeebreak-dante")
    with pytest.raises(DataFormatError) as caught:
        load_dataset(folder)
    assert str(caught.value) == (
        f"{folder / 'features.txt'}: field 'positions': expected metres, people a median of at "
        "most 20 m from their nearest neighbour, found a median of 69.8 (centimetres, read as "
        "metres?); give units='cm' (--units cm) if the file holds centimetres, units='m' if it "
        "holds metres"
    )
    dataset = load_dataset(folder, units="cm")
    np.testing.assert_allclose(dataset.frames[0].position, [[1.767008, 1.357453], [2.46, 1.40]])
    assert dataset.frames[1].groups == ((1, 2),)
    # metres given on purpose are the user's call: read as written
    assert load_dataset(folder, units="m").frames[0].position[0, 0] == pytest.approx(176.7008)


@pytest.mark.parametrize("width", [4, 5])
def test_dante_layout_is_told_by_the_person_tokens_not_the_count(tmp_path, width):
    # 21 tokens: 1 + 5 people × 4 fields, or 1 + 4 people × 5 fields.
    n = 20 // width
    people = " ".join(f"ID_00{k} {k}.0 1.0" + " 0.5" * (width - 3) for k in range(1, n + 1))
    folder = _dante(tmp_path / f"w{width}", [f"0.2 {people}"], ["0.2 < ID_001 ID_002 >"])
    assert len(f"0.2 {people}".split()) == 21
    dataset = load_dataset(folder, format="dante")
    assert dataset.metadata["fields_per_person"] == width
    assert dataset.frames[0].ids.tolist() == list(range(1, n + 1))


def test_dante_line_fitting_no_layout(tmp_path):
    folder = _dante(tmp_path / "bad", ["0.2 ID_001 1.0 2.0 ID_002"], ["0.2 < ID_001 >"])
    with pytest.raises(
        DataFormatError,
        match=r"features.txt: line 1: field 'tokens': expected 1 time token \+ blocks of 4 "
        r"\(ID x y θ\) or 5 \(ID x y body head\) tokens per person, found 5 tokens",
    ):
        load_dante(folder)


def test_dante_nan_person_dropped_and_absent_member_kept(tmp_path):
    folder = _dante(
        tmp_path / "pose",
        ["0.2 ID_001 1.0 1.0 0.0 ID_002 1.5 1.0 3.1 ID_003 nan nan nan"],
        ["0.2 < ID_001 ID_002 ID_003 > < ID_007 >"],
    )
    dataset = load_dante(folder)
    (frame,) = dataset.frames
    assert frame.ids.tolist() == [1, 2]
    assert frame.groups == ((1, 2),) and frame.listed_groups == ((1, 2, 3),)
    assert dataset.metadata["report"]["repairs"] == {
        "people_dropped_nan": 1,
        "groundtruth_members_absent": 2,  # 3 in the group, 7 alone
    }
    with pytest.raises(
        DataFormatError, match=r"line 1, person 3: field 'x'.*found NaN; refused by --strict"
    ):
        load_dante(folder, strict=True)


def test_dante_strict_refuses_salsa_style_repairs(tmp_path):
    folder = _dante(
        tmp_path / "partial",
        ["0.2 ID_001 1.0 1.0 0.0 0.0 ID_002 1.5 1.0 3.1 3.1 ID_003 4.0 4.0 0.0 0.0"],
        ["0.2 < ID_001 ID_002 >"],
    )
    assert load_dante(folder).metadata["report"]["repairs"] == {
        "people_missing_from_groundtruth": 1
    }
    with pytest.raises(
        DataFormatError,
        match=r"group_names.txt: line 1 \(t=0.2\): field 'groups': expected a full partition .*"
        r"found ID 3 in no group; refused by --strict",
    ):
        load_dante(folder, strict=True)


def test_absent_members_survive_the_parquet_round_trip(tmp_path):
    from reform.datasets import read_parquet, write_parquet

    dataset = load_gcff(_gcff(tmp_path / "set", [PEOPLE, PEOPLE], [[[1, 2, 42]], [[2, 3]]]))
    back = read_parquet(write_parquet(dataset, tmp_path / "set.parquet"))
    assert back.frames == dataset.frames
    assert [f.listed_groups for f in back] == [((1, 2, 42),), None]


def test_gcff_angles_a_little_beyond_a_turn_are_wrapped(tmp_path):
    # Cocktail Party's tracker-derived orientations run to 6.8 rad, past [0, 2π).
    people = [[1, 0.0, 0.0, 6.77], [2, 100.0, 0.0, -7.0]]
    (frame,) = load_gcff(_gcff(tmp_path / "set", [people], [[[1, 2]]])).frames
    np.testing.assert_allclose(frame.yaw, [6.77 - 2 * np.pi, -7.0 + 2 * np.pi])


def test_a_mat_file_that_crashes_the_reader_is_one_clean_error(tmp_path):
    # Four zero bytes at offset 232 of this small file make scipy's compiled MATLAB reader
    # crash the process (SIGSEGV, found by test_datasets_fuzz.py): read in a child
    # process, it is one error naming the file.
    folder = _gcff(tmp_path / "set", [PEOPLE[:2]], [[[1, 2]]])
    data = (folder / "features.mat").read_bytes()
    (folder / "features.mat").write_bytes(data[:232] + b"\0\0\0\0" + data[236:])
    with pytest.raises(
        DataFormatError, match=r"features.mat: expected a readable MATLAB .mat file, found"
    ):
        load_gcff(folder)


@pytest.mark.parametrize("kind", ["fifo", "folder", "loop", "device"])
def test_a_file_that_is_not_a_regular_file_is_named_for_what_it_is(tmp_path, kind):
    import os

    folder = tmp_path / "set"
    folder.mkdir()
    (folder / "group_names.txt").write_text("0.2 < ID_001 >\n")
    target = folder / "features.txt"
    if kind == "fifo":
        os.mkfifo(target)  # opening it would wait for a writer forever
    elif kind == "folder":
        target.mkdir()
    elif kind == "loop":
        os.symlink(folder / "b", folder / "a")
        os.symlink(folder / "a", folder / "b")
        os.symlink(folder / "a", target)
    else:
        os.symlink("/dev/zero", target)  # endless
    found = {
        "fifo": r"a FIFO \(named pipe\)",
        "folder": "a folder",
        "loop": "a symbolic link loop",
        "device": "a character device",
    }[kind]
    with pytest.raises(
        DataFormatError,
        match=rf"features.txt: expected a DANTE features file \(a file\), found {found}",
    ):
        load_dataset(folder, format="dante")


def test_a_recording_with_nobody_in_any_frame_is_refused(tmp_path):
    # Every pose NaN (or every slot padding): a damaged file, nothing a detector could be scored
    # on, rather than a scene; one person in one frame is a recording.
    nobody = [[1, np.nan, 0.0, 0.0], [2, np.nan, 0.0, 0.0]]
    gcff = _gcff(tmp_path / "gcff", [nobody, nobody], [[[1, 2]], [[1, 2]]])
    message = (
        r"field 'people': expected someone in at least one frame, found nobody in any of its 2 "
        r"frames \(every pose untracked, NaN or padding\)$"
    )
    with pytest.raises(DataFormatError, match=r"gcff: " + message):
        load_dataset(gcff, units="cm")
    fake = "0.2 fake fake fake fake fake fake fake fake"
    groups = ["0.2 < ID_001 >", "3.2 < ID_001 >"]
    dante = _dante(tmp_path / "dante", [fake, fake.replace("0.2", "3.2", 1)], groups)
    with pytest.raises(DataFormatError, match=r"dante: " + message):
        load_dataset(dante)
    someone = _gcff(tmp_path / "someone", [nobody, [PEOPLE[0]]], [[[1, 2]], [[1]]])
    assert [f.n_people for f in load_dataset(someone, units="cm").frames] == [0, 1]


def test_ground_truth_that_stops_before_the_features_is_said(tmp_path):
    people = "ID_001 1.0 1.0 0.0 ID_002 1.6 1.0 3.1"
    features = [f"{0.2 + 3 * k:.1f} {people}" for k in range(8)]
    group = "< ID_001 ID_002 >"

    def note(annotated: list[int]) -> str | None:
        folder = tmp_path / "-".join(map(str, annotated))
        _dante(folder, features, [f"{0.2 + 3 * k:.1f} {group}" for k in annotated])
        return repairs_line(load_dante(folder), "set")

    assert note([0, 1]) == (
        "note: set: group_names.txt gives no ground truth to 6 lines at the end of features.txt "
        "(session1 from line 3 on): read as frames without groups; is it cut short?"
    )
    assert note(list(range(7))) is None  # the last line alone without ground truth, as SALSA's
    assert note([0, 2, 4, 6]) is None  # every other line annotated, to the end

"""The data model: Frame and Dataset validate at construction and are immutable."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reform import Dataset, Frame, complete_partition, wrap_angle


def _frame(**changes) -> Frame:
    fields = {
        "ids": [3, 1, 2],
        "position": [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        "yaw": [0.0, np.pi, -np.pi / 2],
        "groups": ((3, 1),),
        "time": 1.5,
        "sequence": "s",
    }
    fields.update(changes)
    return Frame(**fields)


def test_a_valid_frame():
    frame = _frame(
        head_position=[[0, 0.1], [np.nan, np.nan], [0, 1.1]], head_yaw=[0.1, np.nan, -1.0]
    )
    assert frame.n_people == 3
    assert frame.ids.dtype == np.int64 and frame.position.dtype == np.float64
    assert frame.kinds == ("human", "human", "human")
    assert frame.annotated
    assert frame.partition() == ((3, 1), (2,))
    assert frame.fformations() == ((3, 1),)
    assert frame.index_of(2) == 2
    assert frame.time == 1.5 and isinstance(frame.time, float)


def test_integral_float_ids_are_accepted():
    assert _frame(ids=[3.0, 1.0, 2.0]).ids.tolist() == [3, 1, 2]
    assert _frame(groups=((3.0, np.int32(1)),)).groups == ((3, 1),)


def test_arrays_are_read_only_copies():
    position = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    frame = _frame(position=position)
    position[0, 0] = 99.0
    assert frame.position[0, 0] == 0.0
    with pytest.raises(ValueError, match="read-only"):
        frame.position[0, 0] = 5.0
    with pytest.raises(AttributeError):
        frame.time = 2.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"ids": [[1, 2, 3]]}, r"ids must have shape \(n_people,\), got \(1, 3\)"),
        ({"ids": [1.5, 2, 3]}, "ids must be integers, got dtype float64"),
        ({"ids": ["a", "b", "c"]}, "ids must be integers"),
        (
            {"ids": [1, 1, 2], "groups": None},
            r"ids must be unique within a frame, got duplicates \[1\]",
        ),
        ({"position": [[0, 0], [1, 0]]}, r"position must have shape \(3, 2\), got \(2, 2\)"),
        ({"position": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}, r"position must have shape \(3, 2\)"),
        ({"position": [[0, np.nan], [1, 0], [0, 1]]}, "position must be finite, got NaN or inf"),
        ({"position": [[0, np.inf], [1, 0], [0, 1]]}, "position must be finite"),
        ({"yaw": [0.0, 0.0]}, r"yaw must have shape \(3,\), got \(2,\)"),
        ({"yaw": [0.0, np.nan, 0.0]}, "yaw must be finite"),
        (
            {"yaw": [0.0, 90.0, 0.0]},
            r"yaw must be radians wrapped to \[-pi, pi\], got 90 .*degrees",
        ),
        ({"yaw": [0.0, 4.0, 0.0]}, "yaw must be radians wrapped"),
        ({"kinds": ("human", "robot")}, "kinds must have 3 entries, got 2"),
        (
            {"kinds": ("human", "dog", "robot")},
            r"kinds must be one of \('human', 'robot'\), got \['dog'\]",
        ),
        (
            {"head_position": [[0, 0], [1, 0], [0, 1]]},
            "head_position and head_yaw must be given together",
        ),
        ({"head_yaw": [0, 0, 0]}, "head_position and head_yaw must be given together"),
        (
            {"head_position": [[0, 0], [1, 0]], "head_yaw": [0, 0]},
            r"head_position must have shape \(3, 2\)",
        ),
        (
            {"head_position": [[0, np.nan], [1, 0], [0, 1]], "head_yaw": [0, 0, 0]},
            "a head is either fully observed",
        ),
        (
            {"head_position": [[0, 0], [1, 0], [0, 1]], "head_yaw": [np.nan, 0, 0]},
            "a head is either fully observed",
        ),
        (
            {"head_position": [[0, 0], [1, np.inf], [0, 1]], "head_yaw": [0, 0, 0]},
            "must be finite or NaN",
        ),
        (
            {"head_position": [[0, 0], [1, 0], [0, 1]], "head_yaw": [0, -7.0, 0]},
            "head_yaw must be radians wrapped",
        ),
        (
            {"groups": ((3, 7),)},
            r"groups\[0\] names person 7, who is not in the frame \(ids \[1, 2, 3\]\)",
        ),
        (
            {"groups": ((3, 1), (1, 2))},
            r"groups must be disjoint, person 1 appears twice \(groups\[1\]\)",
        ),
        ({"groups": ((3, 3),)}, "person 3 appears twice"),
        ({"groups": ((),)}, r"groups\[0\] is empty"),
        ({"groups": ((3, 1.5),)}, r"groups\[0\] must hold integer person ids, got 1.5"),
        ({"groups": ("31",)}, r"groups\[0\] must be a sequence of person ids, got '31'"),
        ({"groups": (3,)}, r"groups\[0\] must be a sequence of person ids, got 3"),
        ({"groups": ((True, 2),)}, r"groups\[0\] must hold integer person ids, got True"),
        ({"time": math.inf}, "time must be finite, got inf"),
        (
            {"position": [[0.0, 0.0], [1e200, 0.0], [0.0, 1.0]]},
            r"position must be metres with \|x\|, \|y\| <= 1e\+08, got x = 1e\+200 for person 1",
        ),
        (
            {"head_position": [[0, 0], [1, 0], [0, -2e8]], "head_yaw": [0, 0, 0]},
            r"head_position must be metres .*got y = -200000000.0 for person 2",
        ),
        ({"time": None}, "time must be a number of seconds, got None"),
    ],
    ids=lambda v: v if isinstance(v, str) and len(v) < 30 else None,
)
def test_invalid_frames_are_rejected(changes, message):
    with pytest.raises(ValueError, match=message):
        _frame(**changes)


def test_wrapped_angles_with_rounding_are_accepted():
    # Babble writes -pi as -3.142: within the tolerance.
    assert _frame(yaw=[-3.142, 3.1416, 0.0]).yaw[0] == -3.142


def test_empty_frame():
    frame = Frame(ids=[], position=np.zeros((0, 2)), yaw=[], groups=())
    assert frame.n_people == 0
    assert frame.partition() == ()
    assert frame.is_robot.shape == (0,)


def test_unannotated_frame():
    frame = _frame(groups=None)
    assert not frame.annotated
    with pytest.raises(ValueError, match="frame is not annotated"):
        frame.partition()
    with pytest.raises(ValueError, match="frame is not annotated"):
        frame.fformations()


def test_index_of_unknown_person():
    with pytest.raises(KeyError, match=r"person 9 is not in this frame \(ids \[3, 1, 2\]\)"):
        _frame().index_of(9)


def test_equality_tells_none_heads_from_nan_heads():
    nan_heads = _frame(head_position=np.full((3, 2), np.nan), head_yaw=np.full(3, np.nan))
    assert nan_heads == _frame(head_position=np.full((3, 2), np.nan), head_yaw=np.full(3, np.nan))
    assert nan_heads != _frame()
    assert _frame() == _frame()
    assert _frame() != _frame(time=2.0)
    assert _frame() != _frame(groups=((1, 3),))  # member order is part of the record
    assert _frame() != _frame(groups=None)
    assert _frame(groups=()) != _frame(groups=None)


def test_replace_validates_again():
    frame = _frame()
    moved = frame.replace(time=9.0)
    assert moved.time == 9.0 and frame.time == 1.5
    with pytest.raises(ValueError, match="names person 1"):
        frame.replace(ids=[3, 4, 2])


def test_robot_kind():
    frame = _frame(kinds=("human", "robot", "human"))
    assert frame.is_robot.tolist() == [False, True, False]


def test_complete_partition_and_wrap_angle():
    assert complete_partition([(5, 2)], [1, 2, 5, 7]) == ((5, 2), (1,), (7,))
    np.testing.assert_allclose(
        wrap_angle([np.pi, -np.pi, 3 * np.pi, 0.5, -7.0]),
        [-np.pi, -np.pi, -np.pi, 0.5, -7.0 + 2 * np.pi],
    )
    assert np.all(wrap_angle(np.linspace(-70, 70, 1001)) < np.pi)


def test_dataset():
    frames = (
        _frame(sequence="a"),
        _frame(sequence="b", groups=None),
        _frame(sequence="a", time=3.0),
    )
    dataset = Dataset(frames=frames, name="d", source="here", metadata={"seed": 1})
    assert len(dataset) == 3 and dataset[1] is frames[1]
    assert list(dataset) == list(frames)
    assert dataset.sequences() == ("a", "b")
    assert dataset.annotated() == (frames[0], frames[2])
    subset = dataset.subset(frames[:1], name="d1")
    assert subset.name == "d1" and subset.metadata == {"seed": 1}
    with pytest.raises(TypeError):
        dataset.metadata["seed"] = 2  # type: ignore[index]


def test_dataset_validation():
    with pytest.raises(
        ValueError, match=r"units must be 'm' \(loaders convert to metres\), got 'cm'"
    ):
        Dataset(frames=(), name="d", units="cm")
    with pytest.raises(TypeError, match=r"frames\[1\] must be a reform.Frame, got dict"):
        Dataset(frames=(_frame(), {}), name="d")  # type: ignore[arg-type]


def test_dataset_times_increase_within_each_sequence():
    a0, b0, a1 = _frame(time=0.0), _frame(sequence="b", time=9.0), _frame(time=0.5)
    assert len(Dataset(frames=(a0, b0, a1), name="d")) == 3  # sequences may interleave
    with pytest.raises(
        ValueError,
        match=r"frames\[2\].time must increase within sequence 's': expected > 0.5 "
        r"\(frames\[0\]\), got 0.0",
    ):
        Dataset(frames=(a1, b0, a0), name="d")
    with pytest.raises(ValueError, match=r"frames\[1\].time .*expected > 0.0 .*got 0.0"):
        Dataset(frames=(a0, a0), name="d")

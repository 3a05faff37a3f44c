"""Frames as columns (reform.FrameBlock): its frames, its checks, and the Parquet file written
from it, the same bytes as the file of its frames written one by one."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from reform import Dataset, Frame, FrameBlock
from reform.datasets import read_parquet, write_parquet


def roster_frames(arrays: dict) -> tuple[Frame, ...]:
    """The frames the arrays stand for: who is present, the groups restricted to them."""
    out = []
    for t in range(arrays["time"].size):
        keep = arrays["present"][t]
        ids = arrays["ids"][keep]
        groups = arrays["groups"][t]
        if groups is not None:
            here = set(ids.tolist())
            groups = tuple(kept for g in groups if (kept := tuple(m for m in g if m in here)))
        head = arrays.get("head_position")
        out.append(
            Frame(
                ids=ids,
                kinds=tuple(k for k, p in zip(arrays["kinds"], keep, strict=True) if p),
                position=arrays["position"][t, keep],
                yaw=arrays["yaw"][t, keep],
                head_position=None if head is None else head[t, keep],
                head_yaw=None if head is None else arrays["head_yaw"][t, keep],
                groups=groups,
                time=float(arrays["time"][t]),
                sequence=arrays["sequence"],
            )
        )
    return tuple(out)


def block(arrays: dict) -> FrameBlock:
    return FrameBlock(**{"head_position": None, "head_yaw": None, **arrays})


def write_both(tmp_path, arrays: dict, metadata=None) -> tuple[bytes, bytes]:
    fast = write_parquet(
        block(arrays), tmp_path / "fast.parquet", name="roster", source="test", metadata=metadata
    )
    dataset = Dataset(
        frames=roster_frames(arrays), name="roster", source="test", metadata=metadata or {}
    )
    slow = write_parquet(dataset, tmp_path / "slow.parquet")
    return fast.read_bytes(), slow.read_bytes()


def example() -> dict:
    """Three people and a robot over five instants: absences, an empty frame, unobserved heads,
    groups naming absent members, an unannotated frame (hand-made)."""
    ids = np.array([4, 9, 2, 0])
    present = np.array(
        [
            [1, 1, 1, 1],
            [1, 0, 1, 1],
            [0, 0, 0, 0],
            [0, 1, 1, 0],
            [1, 1, 0, 1],
        ],
        dtype=bool,
    )
    rng = np.random.default_rng(3)
    head_position = rng.normal(size=(5, 4, 2))
    head_yaw = rng.uniform(-np.pi, np.pi, size=(5, 4))
    head_position[1, 2] = np.nan
    head_yaw[1, 2] = np.nan
    return {
        "time": np.array([0.5, 1.0, 1.5, 2.0, 2.5]),
        "ids": ids,
        "kinds": ("human", "human", "human", "robot"),
        "present": present,
        "position": rng.normal(size=(5, 4, 2)),
        "yaw": rng.uniform(-np.pi, np.pi, size=(5, 4)),
        "head_position": head_position,
        "head_yaw": head_yaw,
        "groups": [((4, 9, 0),), ((9, 4), (2,)), (), None, ((2, 9), (0, 4))],
        "sequence": "episode-0",
    }


def test_same_bytes_as_the_frames_written_one_by_one(tmp_path):
    fast, slow = write_both(tmp_path, example(), metadata={"seed": 3})
    assert fast == slow
    back = read_parquet(tmp_path / "fast.parquet")
    assert back.frames == roster_frames(example())
    assert back.frames[1].groups == ((4,), (2,))  # 9 is absent; member order kept
    assert back.frames[2].n_people == 0 and back.frames[3].groups is None
    assert back.frames[4].groups == ((9,), (0, 4))  # 2 is absent


def test_a_blocks_frames_are_the_frames_it_stands_for():
    made = block(example())
    assert tuple(made.frames()) == roster_frames(example())
    assert [made.frame(t) for t in range(len(made))] == list(roster_frames(example()))
    assert made.present_groups()[1] == ((4,), (2,))


def test_blocks_concatenate_in_order():
    arrays = example()
    first = block({**arrays, **{k: arrays[k][:2] for k in _ROWS}, "groups": arrays["groups"][:2]})
    rest = block({**arrays, **{k: arrays[k][2:] for k in _ROWS}, "groups": arrays["groups"][2:]})
    joined = FrameBlock.concatenate([first, rest])
    assert tuple(joined.frames()) == roster_frames(arrays)
    with pytest.raises(ValueError, match="block 1 differs from block 0 in its roster"):
        FrameBlock.concatenate([first, block({**arrays, "sequence": "other"})])
    with pytest.raises(ValueError, match="at least one block"):
        FrameBlock.concatenate([])


def test_a_block_copies_and_freezes_what_it_is_given():
    arrays = example()
    made = block(arrays)
    arrays["position"][0, 0] = 99.0
    assert made.position[0, 0, 0] != 99.0 and arrays["position"].flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        made.yaw[0, 0] = 1.0


_ROWS = ("time", "present", "position", "yaw", "head_position", "head_yaw")


def test_without_heads_and_without_frames(tmp_path):
    arrays = example()
    del arrays["head_position"], arrays["head_yaw"]
    fast, slow = write_both(tmp_path, arrays)
    assert fast == slow
    arrays = {**example(), "time": np.zeros(0), "groups": []}
    for name in ("present", "position", "yaw", "head_position", "head_yaw"):
        arrays[name] = arrays[name][:0]
    fast, slow = write_both(tmp_path, arrays)
    assert fast == slow


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"ids": np.array([4, 9, 9, 0])}, r"ids must be unique"),
        ({"kinds": ("human", "dog", "human", "robot")}, r"kinds must be 4 entries among"),
        ({"yaw": np.full((5, 4), 7.0)}, r"yaw must be radians wrapped"),
        ({"position": np.full((5, 4, 2), np.inf)}, r"position and yaw must be finite"),
        ({"position": np.full((5, 4, 2), 1e200)}, r"position must be metres with \|x\|, \|y\|"),
        ({"present": np.ones((5, 3), dtype=bool)}, r"present must have shape \(5, 4\)"),
        ({"groups": [None] * 4}, r"groups must have 5 entries"),
        (
            {"groups": [None, ((4, 7),)] + [None] * 3},
            r"groups\[0\] at row 1 names person 7, who is not in the roster \(ids \[0, 2, 4, 9\]\)",
        ),
        (
            {"groups": [((4, 9), (9,))] + [None] * 4},
            r"groups at row 0 must be disjoint, person 9 appears twice \(groups\[1\]\)",
        ),
        ({"groups": [((4, 9), ())] + [None] * 4}, r"groups\[1\] at row 0 is empty"),
        ({"head_yaw": None}, r"given together"),
    ],
    ids=lambda value: str(value)[:30],
)
def test_bad_arrays_are_refused(tmp_path, change, match):
    arrays = {**example(), **change}
    with pytest.raises(ValueError, match=match):
        write_parquet(block(arrays), tmp_path / "bad.parquet", name="x")
    assert not (tmp_path / "bad.parquet").exists()


def test_a_half_observed_head_is_refused(tmp_path):
    arrays = example()
    arrays["head_yaw"] = arrays["head_yaw"].copy()
    arrays["head_yaw"][0, 0] = np.nan
    with pytest.raises(ValueError, match=r"fully observed \(x, y, yaw\) or fully NaN"):
        write_parquet(block(arrays), tmp_path / "bad.parquet", name="x")


@st.composite
def rosters(draw) -> dict:
    n = draw(st.integers(0, 5))
    t = draw(st.integers(0, 6))
    ids = np.array(draw(st.lists(st.integers(0, 10**9), min_size=n, max_size=n, unique=True)))
    present = np.array(draw(st.lists(st.booleans(), min_size=n * t, max_size=n * t)), dtype=bool)
    values = st.floats(-30, 30, allow_nan=False)
    yaws = st.floats(-np.pi, np.pi, allow_nan=False)
    position = np.array(draw(st.lists(values, min_size=2 * n * t, max_size=2 * n * t)))
    yaw = np.array(draw(st.lists(yaws, min_size=n * t, max_size=n * t)))
    hidden = np.array(draw(st.lists(st.booleans(), min_size=n * t, max_size=n * t)), dtype=bool)
    head_yaw = np.where(hidden, np.nan, yaw[::-1] if yaw.size else yaw).reshape(t, n)
    head_position = position[::-1].reshape(t, n, 2).copy()
    head_position[hidden.reshape(t, n)] = np.nan
    groups = []
    for _ in range(t):
        if draw(st.booleans()):
            groups.append(None)
            continue
        order = draw(st.permutations(ids.tolist()))
        cuts = sorted(draw(st.lists(st.integers(0, n), max_size=3)))
        bounds = [0, *cuts, n]
        groups.append(
            tuple(tuple(order[a:b]) for a, b in zip(bounds, bounds[1:], strict=False) if b > a)
        )
    return {
        "time": np.arange(t) * 0.5,
        "ids": ids.astype(np.int64),
        "kinds": tuple(draw(st.sampled_from(["human", "robot"])) for _ in range(n)),
        "present": present.reshape(t, n),
        "position": position.reshape(t, n, 2),
        "yaw": yaw.reshape(t, n),
        "head_position": head_position,
        "head_yaw": head_yaw,
        "groups": groups,
        "sequence": draw(st.sampled_from(["s", "épisode 2"])),
    }


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(arrays=rosters())
def test_same_bytes_property(tmp_path, arrays):
    fast, slow = write_both(tmp_path, arrays)
    assert fast == slow

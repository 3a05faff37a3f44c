"""A FrameBlock works out the groups of the people present once: every caller (the Parquet
writer, a generated shard's summary and events) is given the same answer, which is the groups
of the block's frames."""

from __future__ import annotations

import numpy as np

from reform import FrameBlock


def _block() -> FrameBlock:
    """Three people over four instants: one leaves, the groups change, one instant unannotated
    (hand-made)."""
    present = np.array([[1, 1, 1], [1, 1, 0], [1, 1, 0], [1, 1, 1]], dtype=bool)
    return FrameBlock(
        time=[0.0, 0.5, 1.0, 1.5],
        ids=[3, 5, 8],
        kinds=("human", "human", "robot"),
        present=present,
        position=np.zeros((4, 3, 2)),
        yaw=np.zeros((4, 3)),
        head_position=None,
        head_yaw=None,
        groups=(((3, 5, 8),), ((3, 5, 8),), None, ((3,), (5, 8))),
        sequence="s",
    )


def test_the_groups_of_the_people_present_are_those_of_the_frames():
    block = _block()
    expected = (((3, 5, 8),), ((3, 5),), None, ((3,), (5, 8)))
    assert block.present_groups() == expected
    assert tuple(frame.groups for frame in block.frames()) == expected


def test_every_caller_is_given_the_same_answer():
    block = _block()
    assert block.present_groups() is block.present_groups()
    joined = FrameBlock.concatenate([block, _shifted(block)])
    assert joined.present_groups() == block.present_groups() * 2


def _shifted(block: FrameBlock) -> FrameBlock:
    """``block`` two seconds later."""
    fields = {
        name: getattr(block, name)
        for name in ("ids", "kinds", "present", "position", "yaw", "head_position", "head_yaw")
    }
    return FrameBlock(time=block.time + 2.0, groups=block.groups, sequence="s", **fields)

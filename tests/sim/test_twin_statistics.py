"""The twins' detector statistics (`sim.twins.statistics.detector_shape`): how fixed detectors
group a recording and how much they agree, read without its labels; and the clumps the spacing
statistics count."""

from __future__ import annotations

import numpy as np
import pytest

from reform.frame import Frame
from sim.twins.statistics import (
    DETECTOR_SHAPE_SIZE,
    SMALL_CLUMP_PEOPLE,
    _clump_sizes,
    detector_shape,
)


def _two_pairs(gap: float, *, groups=None, frames: int = 5) -> list[Frame]:
    """Two pairs facing each other across 0.8 m, one ``gap`` metres beside the other."""
    position = np.array([[0.0, 0.0], [0.8, 0.0], [0.0, gap], [0.8, gap]])
    yaw = np.array([0.0, np.pi, 0.0, np.pi])
    return [
        Frame(ids=np.arange(4), position=position, yaw=yaw, groups=groups, time=float(t),
              sequence="s")
        for t in range(frames)
    ]  # fmt: skip


def test_pairs_far_apart_are_two_groups_every_detector_agrees_on():
    assert detector_shape(_two_pairs(5.0)).tolist() == [1.0, 2.0, 1.0, 1.0]


def test_people_alone_are_no_group_and_no_disagreement():
    position = np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0], [5.0, 5.0]])
    frames = [
        Frame(ids=np.arange(4), position=position, yaw=np.zeros(4), time=float(t), sequence="s")
        for t in range(3)
    ]
    assert detector_shape(frames).tolist() == [0.0, 1.0, 1.0, 1.0]


def test_detectors_that_group_a_close_crowd_differently_disagree():
    # A metre apart, GCFF sees one o-space of four; the proximity baseline sees the two pairs.
    share, size, short_stride, proximity = detector_shape(_two_pairs(1.0))
    assert (share, size, short_stride) == (1.0, 4.0, 1.0)
    assert proximity < 0.5


@pytest.mark.parametrize("groups", [((0, 1), (2, 3)), ((0, 2), (1, 3)), ((0, 1, 2, 3),)])
def test_the_labels_are_never_read(groups):
    assert detector_shape(_two_pairs(1.0, groups=groups)).tolist() == (
        detector_shape(_two_pairs(1.0)).tolist()
    )


def test_frames_of_fewer_than_four_people_say_nothing():
    two = [Frame(ids=np.arange(2), position=np.array([[0.0, 0.0], [0.8, 0.0]]),
                 yaw=np.array([0.0, np.pi]), time=0.0, sequence="s")]  # fmt: skip
    shape = detector_shape(two)
    assert shape.shape == (DETECTOR_SHAPE_SIZE,) and np.isnan(shape).all()


def _distances(points: np.ndarray) -> np.ndarray:
    d = np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    return d


@pytest.mark.parametrize("people", [1, 2, 7, SMALL_CLUMP_PEOPLE, SMALL_CLUMP_PEOPLE + 1, 90])
def test_clumps_are_scipys_connected_components(people):
    """The squared links of a small frame and scipy's routine for a large one give the same
    clumps: random crowds, a single chain (the longest path to follow), everyone linked and
    no one."""
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(people)
    chain = np.stack([np.arange(people) * 0.9, np.zeros(people)], axis=1)
    frames = [rng.uniform(0.0, 6.0, size=(people, 2)) for _ in range(20)] + [chain]
    for points in frames:
        d = _distances(points)
        for link in (0.01, 0.5, 1.0, 100.0):
            _, label = connected_components(d < link, directed=False)
            assert _clump_sizes(d, link).tolist() == np.bincount(label)[label].tolist()

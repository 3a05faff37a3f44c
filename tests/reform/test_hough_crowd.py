"""HVFF and multi-scale HVFF on crowds: beyond ``CROWD_PEOPLE`` people the accumulator is read
part by part (people joined by a centre they own or back). It must give the labels of the dense
whole-frame accumulator, numbering included: on random crowds, on groups just inside and just
outside the distance at which one group's votes back the other's centre, on several separated
clusters, and on exact ties within and between parts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import reform.hough as hough
from reform import Frame, wrap_angle
from reform.hough import (
    MIN_SHARE,
    RADIUS_M,
    STRIDE_M,
    MultiScaleHvff,
    hough_labels,
    scale_strides,
    vote_noise,
)

HVFF = {"strides": [STRIDE_M], "sizes": [(2, np.iinfo(np.int64).max)]}
MULTISCALE = {
    "strides": scale_strides(1.0, 6).tolist(),
    "sizes": [(k, k) for k in range(2, 6)] + [(6, np.iinfo(np.int64).max)],
}
SCALES = {"hvff": HVFF, "hvff-multiscale": MULTISCALE}


def both_paths(position, yaw, *, scales, noise, radius=RADIUS_M):
    """The labels of the whole-frame accumulator and of the part-by-part reading."""
    offset, turn = noise
    run = {"offset": offset, "turn": turn, "radius": radius, "min_share": MIN_SHARE, **scales}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(hough, "CROWD_PEOPLE", 10**9)
        whole = hough_labels(position, yaw, **run)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(hough, "CROWD_PEOPLE", 0)
        parts = hough_labels(position, yaw, **run)
    return whole, parts


def noise(seed: int = 0, *, exact: bool = False, samples: int = 100):
    sd = (0.0, 0.0) if exact else (hough.POSITION_SD_M, hough.ORIENTATION_SD_RAD)
    rng = np.random.default_rng(seed)
    return vote_noise(rng, samples=samples, position_sd=sd[0], orientation_sd=sd[1])


def circles(n: int, seed: int, *, density_per_m2: float) -> tuple[np.ndarray, np.ndarray]:
    """``n`` people (metres, radians): circles of 2-6 facing their centre, and loners."""
    rng = np.random.default_rng(seed)
    side = math.sqrt(n / density_per_m2)
    position, yaw = [], []
    while len(yaw) < n:
        size = int(min(rng.integers(1, 7), n - len(yaw)))
        centre = rng.uniform(0, side, 2)
        phase = rng.uniform(0, 2 * math.pi)
        for m in range(size):
            a = phase + 2 * math.pi * m / size + rng.normal(0, 0.2)
            p = centre + (0.45 + 0.1 * size) * np.array([math.cos(a), math.sin(a)]) * (size > 1)
            position.append(p + rng.normal(0, 0.05, 2))
            facing = math.atan2(*(centre - p)[::-1]) if size > 1 else rng.uniform(-4, 4)
            yaw.append(facing + rng.normal(0, 0.2))
    return np.array(position), wrap_angle(np.array(yaw))


@settings(max_examples=12, deadline=None)
@given(
    n=st.integers(2, 150),
    density=st.sampled_from([0.05, 0.3, 1.0, 3.0]),
    seed=st.integers(0, 2**32 - 1),
    name=st.sampled_from(sorted(SCALES)),
)
def test_random_crowds_give_the_whole_frame_labels(n, density, seed, name):
    position, yaw = circles(n, seed, density_per_m2=density)
    whole, parts = both_paths(position, yaw, scales=SCALES[name], noise=noise(seed))
    np.testing.assert_array_equal(parts, whole)


@settings(max_examples=12, deadline=None)
@given(
    spacing=st.sampled_from([0.5, 0.7, 1.0, 1.4]),
    fill=st.sampled_from([0.3, 0.7, 1.0]),
    seed=st.integers(0, 2**32 - 1),
    name=st.sampled_from(sorted(SCALES)),
)
def test_lattices_of_exact_votes_tie_everywhere(spacing, fill, seed, name):
    # People on a square lattice facing along its axes, votes without noise: many centres hold
    # the same shares and the same scores, within a part and across parts.
    rng = np.random.default_rng(seed)
    cells = np.stack(np.meshgrid(np.arange(10), np.arange(10)), axis=-1).reshape(-1, 2)
    cells = cells[rng.random(len(cells)) < fill]
    if len(cells) < 2:
        return
    position = spacing * cells.astype(float)
    yaw = wrap_angle(rng.integers(0, 4, len(cells)) * (np.pi / 2))
    whole, parts = both_paths(
        position, yaw, scales=SCALES[name], noise=noise(exact=True, samples=16)
    )
    np.testing.assert_array_equal(parts, whole)


def facing_pair(centre: np.ndarray, stride: float) -> tuple[np.ndarray, np.ndarray]:
    """Two people facing each other along x, each ``stride`` from ``centre``."""
    position = np.array([centre - [stride, 0.0], centre + [stride, 0.0]])
    return position, np.array([0.0, np.pi])


@pytest.mark.parametrize("name", sorted(SCALES))
@pytest.mark.parametrize("side", [-1, 1], ids=["just-inside", "just-outside"])
def test_groups_just_inside_and_just_outside_each_others_centre(name, side):
    # Without noise every vote of a pair lands on its o-space point; a person whose point is
    # d from a centre holds a share 1 - (d / radius)² there, a backer's share at
    # d = radius * sqrt(1 - MIN_SHARE). Pairs whose points stand just closer (one part, four
    # people backing each other's centres, tied scores) or just farther (a part per pair) than
    # that, in a row of such pairs and far from a second row.
    stride = SCALES[name]["strides"][0]
    reach = RADIUS_M * math.sqrt(1.0 - MIN_SHARE) * (1.0 + side * 1e-9)
    position, yaw = [], []
    for row in range(2):
        for k in range(4):
            p, y = facing_pair(np.array([k * reach, 40.0 * row]), stride)
            position.append(p)
            yaw.append(y)
    position, yaw = np.concatenate(position), np.concatenate(yaw)
    whole, parts = both_paths(
        position, yaw, scales=SCALES[name], noise=noise(exact=True, samples=16)
    )
    np.testing.assert_array_equal(parts, whole)


@pytest.mark.parametrize("name", sorted(SCALES))
def test_exact_ties_between_parts_are_taken_in_row_order(name):
    # Identical pairs far apart hold identical shares (1 each, noise-free votes on one point):
    # every part's best centre ties; the whole frame takes them in row order, and so must the
    # merge of the parts (the labels say in which order groups were taken).
    stride = SCALES[name]["strides"][0]
    pairs = [facing_pair(np.array([100.0 * k, 0.0]), stride) for k in (3, 0, 2, 1)]
    position = np.concatenate([p for p, _ in pairs])
    yaw = np.concatenate([y for _, y in pairs])
    whole, parts = both_paths(
        position, yaw, scales=SCALES[name], noise=noise(exact=True, samples=16)
    )
    assert whole.tolist() == [0, 0, 1, 1, 2, 2, 3, 3]
    np.testing.assert_array_equal(parts, whole)


@pytest.mark.parametrize("name", sorted(SCALES))
def test_separated_clusters_each_with_its_own_crowd(name):
    # Five dense clusters 60 m apart, each a crowd of its own, people interleaved in row order.
    rng = np.random.default_rng(11)
    position, yaw = [], []
    for k in range(5):
        p, y = circles(30, 100 + k, density_per_m2=1.5)
        position.append(p + [60.0 * k, 0.0])
        yaw.append(y)
    order = rng.permutation(150)
    position, yaw = np.concatenate(position)[order], np.concatenate(yaw)[order]
    whole, parts = both_paths(position, yaw, scales=SCALES[name], noise=noise(3))
    np.testing.assert_array_equal(parts, whole)
    assert len(set(whole.tolist())) < 150  # groups were found


def test_the_detector_reads_crowds_part_by_part(monkeypatch):
    # Through the estimator: a frame beyond CROWD_PEOPLE gets the groups of the dense reading.
    position, yaw = circles(90, 5, density_per_m2=0.5)
    scene = Frame(ids=np.arange(1, position.shape[0] + 1), position=position, yaw=yaw)
    detector = MultiScaleHvff()
    monkeypatch.setattr(hough, "CROWD_PEOPLE", 60)
    crowd = detector.predict([scene])
    monkeypatch.setattr(hough, "CROWD_PEOPLE", 10**9)
    assert crowd == detector.predict([scene])
    assert any(len(g) > 1 for g in crowd[0])

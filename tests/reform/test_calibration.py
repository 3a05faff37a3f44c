"""Calibration statistics (reform.calibration): hand-computed cases, invariants, real data."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from reform import Frame
from reform.calibration import (
    IN_GROUP,
    MIN_GROUPS,
    OUT_OF_GROUP,
    PAPER_CHARACTERISATION,
    SYMMETRY,
    TIGHTNESS,
    anova_by_size,
    characterise_dataset,
    compare,
    eligible_sizes,
    pair_feature_samples,
    paper_characterisation_for,
    tukey_by_size,
)
from reform.features import DISTANCE, EFFORT_ANGLE


def _pair(distance: float, *, x0: float = 0.0) -> np.ndarray:
    return np.array([[x0, 0.0], [x0 + distance, 0.0]])


def _triangle(radius: float, *, x0: float = 0.0) -> np.ndarray:
    angles = np.radians([90.0, 210.0, 330.0])
    return np.column_stack([np.cos(angles), np.sin(angles)]) * radius + [x0, 0.0]


def _frame_of_groups(groups: list[np.ndarray], *, time: float = 0.0) -> Frame:
    """One frame holding each (n, 2) member array as an F-formation, facing its centre."""
    positions, yaws, members = [], [], []
    next_id = 0
    for group in groups:
        centre = group.mean(axis=0)
        ids = tuple(range(next_id, next_id + len(group)))
        next_id += len(group)
        positions.append(group)
        yaws.append(np.arctan2(centre[1] - group[:, 1], centre[0] - group[:, 0]))
        members.append(ids)
    return Frame(
        ids=np.arange(next_id),
        position=np.concatenate(positions),
        yaw=np.concatenate(yaws),
        groups=tuple(members),
        time=time,
    )


def _random_frames(seed: int, n_frames: int = 6) -> list[Frame]:
    """Seeded frames of 9 people: a group of 2, a group of 3, a group of 4, facing inwards."""
    rng = np.random.default_rng(seed)
    frames = []
    for t in range(n_frames):
        groups = []
        for k, size in enumerate((2, 3, 4)):
            angles = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(size) / size
            angles += rng.normal(scale=0.2, size=size)
            radius = rng.uniform(0.4, 1.0)
            groups.append(np.column_stack([np.cos(angles), np.sin(angles)]) * radius + [5.0 * k, 0])
        frames.append(_frame_of_groups(groups, time=float(t)))
    return frames


# --- characterise_dataset ------------------------------------------------------------------


def test_characterisation_by_size_is_hand_computed():
    # Hand-computed: pairs 2 m and 4 m apart have Tightness 1 and 2 (mean 1.5, sample sd
    # sqrt(0.5)); equilateral triangles of circumradius 1 have Tightness 1 and Symmetry 0.
    frames = [
        _frame_of_groups([_pair(2.0), _triangle(1.0, x0=10.0)]),
        _frame_of_groups([_pair(4.0)]).replace(time=1.0),
        _frame_of_groups([_pair(9.0)]).replace(groups=None),  # not annotated: skipped
    ]
    result = characterise_dataset(frames, name="hand")
    assert result.name == "hand" and result.frames == 2 and result.fformations == 3
    assert result.sizes() == (2, 3)
    pairs = result.by_size()[2]
    assert (pairs.count, pairs.tightness_mean, pairs.symmetry_mean) == (2, 1.5, 0.0)
    assert pairs.tightness_std == pytest.approx(math.sqrt(0.5))
    triangles = result.by_size()[3]
    assert triangles.count == 1
    assert triangles.tightness_mean == pytest.approx(1.0)
    assert triangles.symmetry_mean == pytest.approx(0.0, abs=1e-9)
    assert math.isnan(triangles.tightness_std)  # one group: no sample sd
    assert result.samples(TIGHTNESS, 2).tolist() == [1.0, 2.0]
    assert result.count(7) == 0 and math.isnan(result.mean(TIGHTNESS, 7))
    summary = result.to_json()
    assert summary["by_size"][1]["tightness_std_m"] is None
    assert summary["pairs"] == 10 + 1  # C(5, 2) pairs + C(2, 2)


def test_pair_feature_samples_are_hand_computed_frame_by_frame():
    # Hand-computed. A at (0, 0) facing +x, B at (2, 0) facing -x: d = 2, EA = 0, together.
    # C at (0, 3) facing +x: (A, C) d = 3, both turn 90 degrees, EA = pi.
    # (B, C) d = sqrt(13); B turns atan(3/2) and so does C, EA = 2 atan(1.5).
    three = Frame(
        ids=[1, 2, 3],
        position=[[0.0, 0.0], [2.0, 0.0], [0.0, 3.0]],
        yaw=[0.0, np.pi, 0.0],
        groups=((1, 2),),
    )
    two = Frame(ids=[7, 8], position=[[0.0, 0.0], [0.0, 1.0]], yaw=[0.0, 0.0], groups=())
    unannotated = two.replace(groups=None)
    samples = pair_feature_samples([three, unannotated, two, three])
    distance, effort, label = samples  # unpacks like a tuple
    np.testing.assert_allclose(
        distance, [2.0, 3.0, math.sqrt(13.0), 1.0] + [2.0, 3.0, math.sqrt(13.0)]
    )
    ea = [0.0, math.pi, 2 * math.atan(1.5)]
    np.testing.assert_allclose(effort, ea + [math.pi] + ea, atol=1e-12)
    assert label.tolist() == [1, 0, 0, 0, 1, 0, 0]
    assert not distance.flags.writeable
    assert samples.select(DISTANCE, IN_GROUP).tolist() == [2.0, 2.0]
    assert samples.select(EFFORT_ANGLE, OUT_OF_GROUP).size == 5
    with pytest.raises(ValueError, match="kind must be one of"):
        samples.select(DISTANCE, "together")
    with pytest.raises(ValueError, match="feature must be one of"):
        samples.select("speed", IN_GROUP)


def test_pair_feature_samples_of_nothing_are_empty():
    samples = pair_feature_samples([])
    assert samples.distance.shape == (0,) and samples.label.dtype == np.int64


# --- ANOVA and Tukey ------------------------------------------------------------------------


def _two_sizes() -> list[Frame]:
    # Tightness 1, 2, 3 for pairs (2, 4, 6 m apart) and 4, 5, 6 for triangles (circumradius).
    return [
        _frame_of_groups([_pair(2.0 * k), _triangle(3.0 + k, x0=50.0)], time=float(k))
        for k in (1, 2, 3)
    ]


def test_anova_is_hand_computed():
    # Hand-computed: means 2 and 5, grand mean 3.5; SSB = 2 * 3 * 1.5^2 = 13.5 (df 1),
    # SSW = 2 + 2 = 4 (df 4), F = 13.5 / (4 / 4) = 13.5.
    result = anova_by_size(characterise_dataset(_two_sizes()), min_groups=3)
    assert result.sizes == (2, 3)
    assert (result.df_between, result.df_within) == (1, 4)
    assert result.statistic == pytest.approx(13.5)
    assert result.pvalue == pytest.approx(stats.f.sf(13.5, 1, 4))


def test_tukey_of_two_sizes_is_the_t_interval():
    # Hand-computed: with two sizes Tukey's HSD is the pooled t test: difference 5 - 2 = 3,
    # MSW = 1, standard error sqrt(1/3 + 1/3), interval 3 -+ t(0.975, 4) * sqrt(2/3).
    result = tukey_by_size(characterise_dataset(_two_sizes()), min_groups=3)
    (entry,) = result.pairs
    assert (entry.size_a, entry.size_b) == (2, 3)
    assert entry.difference == pytest.approx(3.0)
    half = stats.t.ppf(0.975, 4) * math.sqrt(2.0 / 3.0)
    assert (entry.ci_low, entry.ci_high) == pytest.approx((3.0 - half, 3.0 + half), rel=1e-4)
    assert entry.pvalue == pytest.approx(stats.f.sf(13.5, 1, 4), rel=1e-3)
    assert result.pair(3, 2) is entry


def test_symmetry_tests_leave_pairs_out_and_thin_sizes_need_asking():
    result = characterise_dataset(_random_frames(3, n_frames=6))
    assert eligible_sizes(result, measure=TIGHTNESS) == (2, 3, 4)
    assert eligible_sizes(result, measure=SYMMETRY) == (3, 4)
    assert eligible_sizes(result, measure=TIGHTNESS, min_groups=7) == ()
    assert anova_by_size(result, measure=SYMMETRY).sizes == (3, 4)
    with pytest.raises(
        ValueError, match=r"at least two group sizes with >= 7 F-formations, got \[\]"
    ):
        anova_by_size(result, min_groups=7)
    with pytest.raises(ValueError, match=r"at least 2 F-formations .* got \[\(5, 0\)\]"):
        tukey_by_size(result, sizes=(2, 5))
    with pytest.raises(ValueError, match="measure must be one of"):
        anova_by_size(result, measure="radius")
    with pytest.raises(ValueError, match=r"confidence_level must be in \(0, 1\), got 95"):
        tukey_by_size(result, confidence_level=95)


# --- compare --------------------------------------------------------------------------------


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_dataset_compared_with_itself_differs_by_nothing(seed):
    frames = _random_frames(seed)
    result = compare(frames, frames)
    for size, diff in result.tightness_difference().items():
        assert diff == 0.0, size
    assert all(d == 0.0 for d in result.symmetry_difference().values())
    for entry in result.ks:
        assert entry.statistic == 0.0 and entry.pvalue == 1.0
    assert result.within_tolerance(1e-12, min_groups=1)


def _scaled(frames: list[Frame], factor: float) -> list[Frame]:
    return [f.replace(position=f.position * factor) for f in frames]


def test_scaling_the_scene_moves_tightness_and_distance_but_not_effort_angle():
    # Doubling every coordinate is exact in floating point and leaves every angle unchanged.
    reference = _random_frames(11)
    candidate = _scaled(reference, 2.0)
    result = compare(candidate, reference)
    for size, diff in result.tightness_difference().items():
        assert diff == pytest.approx(result.reference.mean(TIGHTNESS, size))
    for size, diff in result.symmetry_difference().items():
        assert diff == pytest.approx(0.0, abs=1e-9), size
    assert result.ks_result(EFFORT_ANGLE, IN_GROUP).statistic == 0.0
    assert result.ks_result(EFFORT_ANGLE, OUT_OF_GROUP).statistic == 0.0
    in_group = result.ks_result(DISTANCE, IN_GROUP)
    assert in_group.statistic > 0.0
    assert in_group.candidate_median == pytest.approx(2.0 * in_group.reference_median)


def _pairs_with_tightness(values: list[float]) -> list[Frame]:
    return [_frame_of_groups([_pair(2.0 * v)], time=float(k)) for k, v in enumerate(values)]


def test_within_tolerance_checks_every_reference_size_with_enough_groups():
    reference = _pairs_with_tightness([1.0] * MIN_GROUPS) + [_frame_of_groups([_triangle(3.0)])]
    close = compare(_pairs_with_tightness([1.05] * MIN_GROUPS), reference)
    assert close.reference_sizes() == (2,)  # one triangle: too few to check
    assert close.within_tolerance() and close.failures() == ()
    assert close.tightness_difference()[2] == pytest.approx(0.05)
    assert math.isnan(close.tightness_difference()[3])  # the candidate has no triangle

    far = compare(_pairs_with_tightness([1.15] * MIN_GROUPS), reference)
    assert not far.within_tolerance()
    (reason,) = far.failures()
    assert reason == (
        "size 2: mean Tightness 1.150 m vs reference 1.000 m (difference +0.150 m, tolerance 0.1 m)"
    )
    assert far.within_tolerance(0.2)

    thin = compare(_pairs_with_tightness([1.0] * (MIN_GROUPS - 1)), reference)
    assert thin.failures() == (f"size 2: candidate has {MIN_GROUPS - 1} F-formations, needs >= 5",)
    strict = compare(_pairs_with_tightness([1.0] * MIN_GROUPS), reference)
    assert "size 3: candidate has 0 F-formations" in strict.failures(min_groups=1)[0]
    with pytest.raises(ValueError, match="tol_m must be a positive number of metres, got -0.1"):
        strict.within_tolerance(-0.1)


def test_comparison_json_is_strict_json():
    import json

    reference = _random_frames(5)
    result = compare(reference[:2], reference)
    text = json.dumps(result.to_json(), allow_nan=False)
    loaded = json.loads(text)
    assert loaded["within_tolerance"] is False  # 2 groups of each size, fewer than MIN_GROUPS
    assert [k["kind"] for k in loaded["ks"]] == [IN_GROUP, OUT_OF_GROUP, IN_GROUP, OUT_OF_GROUP]


def test_compare_accepts_a_ready_characterisation():
    frames = _random_frames(8)
    reference = characterise_dataset(frames, name="ref")
    result = compare(frames, reference)
    assert result.reference is reference and result.reference.name == "ref"


# --- the paper's numbers --------------------------------------------------------------------


def test_paper_numbers_are_the_published_ones():
    # Paper, section "F-Formation Characteristics" (definitions.md, "The paper's numbers").
    babble, salsa = PAPER_CHARACTERISATION["babble"], PAPER_CHARACTERISATION["salsa"]
    assert babble.tightness_m[2] == 0.78 and babble.tightness_m[7] == 0.95
    assert salsa.tightness_m[2] == 0.44 and salsa.tightness_m[7] == 0.93
    assert babble.symmetry_deg[3] == 234.0 and salsa.symmetry_deg[3] == 50.0
    assert salsa.symmetry_anova.df_within == 1639
    assert paper_characterisation_for("SALSA") is salsa
    assert paper_characterisation_for("coffeebreak") is None
    assert math.isnan(babble.mean(SYMMETRY, 2))


# --- real data ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def salsa(salsa_dataset):
    return characterise_dataset(salsa_dataset)


@pytest.fixture(scope="module")
def babble(babble_dataset):
    return characterise_dataset(babble_dataset)


def test_salsa_characterisation(salsa):
    # Group counts: this project's SALSA loader (canonical ground truth), 1,143 annotated frames.
    assert salsa.frames == 1143
    counts = {s: salsa.count(s) for s in salsa.sizes()}
    assert counts == {2: 1554, 3: 1705, 4: 952, 5: 539, 6: 381, 7: 238, 8: 25, 12: 1}
    assert salsa.pairs.label.size == 1143 * 153
    tight = [salsa.mean(TIGHTNESS, s) for s in range(2, 9)]
    assert tight == sorted(tight)  # larger groups stand looser
    assert anova_by_size(salsa).pvalue < 1e-4


def test_salsa_session2_reproduces_the_papers_tightness(salsa_dataset):
    # The paper's SALSA Tightness means are those of session 2 (its 500 frames), to 0.01 m.
    session2 = characterise_dataset([f for f in salsa_dataset if f.sequence == "session2"])
    paper = PAPER_CHARACTERISATION["salsa"]
    for size, value in paper.tightness_m.items():
        assert session2.mean(TIGHTNESS, size) == pytest.approx(value, abs=0.01), size


def test_babble_characterisation(babble):
    # Group counts: Babble's annotated-frames.csv, the duplicated line 2840 counted once.
    counts = {s: babble.count(s) for s in babble.sizes()}
    assert counts == {2: 8, 3: 18, 4: 10, 5: 20, 6: 15, 7: 23}
    tight = [babble.mean(TIGHTNESS, s) for s in babble.sizes()]
    assert tight == sorted(tight)
    assert tukey_by_size(babble).pair(2, 7).pvalue < 1e-4


def test_salsa_groups_are_tighter_than_babbles(salsa, babble):
    result = compare(salsa, babble)
    assert all(diff < -0.1 for diff in result.tightness_difference().values())
    assert not result.within_tolerance()
    assert len(result.failures()) == 6  # every Babble size
    assert result.ks_result(DISTANCE, IN_GROUP).statistic > 0.3


def test_pair_labels_agree_with_the_metrics_definition(salsa_dataset):
    from reform.metrics import pair_labels

    listed_alone = Frame(
        ids=[4, 9, 2, 7],
        position=[[0, 0], [1, 0], [2, 0], [3, 0]],
        yaw=np.zeros(4),
        groups=((9,), (2, 4, 7)),
    )
    frames = [listed_alone, *salsa_dataset.annotated()[:200]]
    expected = np.concatenate([pair_labels(f) for f in frames])
    np.testing.assert_array_equal(pair_feature_samples(frames).label, expected)

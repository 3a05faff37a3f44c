"""GCFF: faithful to the reference code on SALSA, hand-worked scenes, invariants, units, tuning."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from gcff_reference import read_reference_partitions
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone
from sklearn.exceptions import NotFittedError

import reform.gcff as gcff_module
from reform import T_ONE, T_TWO_THIRDS, DataFormatError, Frame, Gcff, evaluate
from reform.gcff import (
    alpha_expansion,
    energy,
    gcff_labels,
    grid_search,
    segment_points,
    unary_costs,
)

# The original code's answers (franzsetti/GCFF @ da29a129 under GNU Octave 7.3, body orientation,
# SALSA positions x 100 = cm) and their scores, from ../shared/reference/gcff-reference/README.md.
REFERENCE = {
    "salsa-body-stride70cm-mdl10000.txt": {
        "params": {"stride": 0.7, "mdl": 1.0},
        T_TWO_THIRDS: (0.848, 0.847, 0.847),
        T_ONE: (0.651, 0.651, 0.651),
    },
    "salsa-body-stride50cm-mdl20000.txt": {
        "params": {"stride": 0.5, "mdl": 2.0},
        T_TWO_THIRDS: (0.842, 0.823, 0.833),
        T_ONE: (0.643, 0.631, 0.637),
    },
}


def as_sets(partition) -> frozenset[frozenset[int]]:
    return frozenset(frozenset(int(m) for m in group) for group in partition)


def label_sets(labels) -> frozenset[frozenset[int]]:
    groups: dict[int, set[int]] = {}
    for row, label in enumerate(np.asarray(labels).tolist()):
        groups.setdefault(label, set()).add(row)
    return frozenset(frozenset(g) for g in groups.values())


def read_reference(path: Path) -> list[tuple[tuple[str, float], frozenset[frozenset[int]]]]:
    """The reference file's partitions as sets: [((sequence, time), partition)]."""
    return [(key, as_sets(groups)) for key, groups in read_reference_partitions(path)]


@pytest.fixture(scope="module")
def salsa_frames(salsa_dataset):
    return salsa_dataset.annotated()


@pytest.fixture(scope="module")
def reference_runs(salsa_frames, gcff_reference_dir):
    """Our predictions and the reference's, per reference file (computed once)."""
    runs = {}
    for name, spec in REFERENCE.items():
        reference = read_reference(gcff_reference_dir / name)
        predictions = Gcff(**spec["params"]).predict(salsa_frames)
        runs[name] = (reference, predictions)
    return runs


# ---------------------------------------------------------------------------------------------
# Faithful to the original code
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(REFERENCE))
def test_reproduces_reference_partitions_on_every_salsa_frame(name, salsa_frames, reference_runs):
    reference, predictions = reference_runs[name]
    assert len(reference) == len(salsa_frames) == 1143
    assert [key for key, _ in reference] == [(f.sequence, f.time) for f in salsa_frames]
    mismatched = [
        (frame.sequence, frame.time)
        for frame, (_, expected), predicted in zip(
            salsa_frames, reference, predictions, strict=True
        )
        if as_sets(predicted) != expected
    ]
    assert mismatched == []


@pytest.mark.parametrize("name", list(REFERENCE))
def test_reproduces_reference_scores(name, salsa_frames, reference_runs):
    _, predictions = reference_runs[name]
    evaluation = evaluate(salsa_frames, predictions)
    for threshold in (T_TWO_THIRDS, T_ONE):
        scores = evaluation.at(threshold)
        rounded = (round(scores.precision, 3), round(scores.recall, 3), round(scores.f1, 3))
        assert rounded == REFERENCE[name][threshold]


# ---------------------------------------------------------------------------------------------
# Hand-worked scenes (metres, default stride 0.7 m = 70 cm, mdl 1 m² = 10,000 cm²)
# ---------------------------------------------------------------------------------------------


def groups_of(position, yaw, **params) -> frozenset[frozenset[int]]:
    params = {"stride": 0.7, "mdl": 1.0} | params
    return label_sets(gcff_labels(np.asarray(position, float), np.asarray(yaw, float), **params))


def test_face_to_face_pair_is_one_group_with_hand_computed_energy():
    # A at 0 facing +x, B at 120 cm facing -x: segment points at 70 and 50 cm, centre 60 cm;
    # each is 10 cm from it (100 cm²), nobody hides anyone (opposite sides, cos = -1).
    position_cm = np.array([[0.0, 0.0], [120.0, 0.0]])
    yaw = np.array([0.0, math.pi])
    assert groups_of(position_cm / 100, yaw) == {frozenset({0, 1})}
    points = segment_points(position_cm, yaw, stride=70.0)
    np.testing.assert_allclose(points, [[70.0, 0.0], [50.0, 0.0]], atol=1e-12)
    together = unary_costs(points, position_cm, np.array([0, 0]), mdl=10_000.0)
    np.testing.assert_allclose(together, [[100.0], [100.0]], atol=1e-9)
    assert energy(together, [0, 0], label_cost=10_000.0) == pytest.approx(10_200.0)
    apart = unary_costs(points, position_cm, np.array([0, 1]), mdl=10_000.0)
    np.testing.assert_allclose(apart, [[0.0, 400.0], [400.0, 0.0]], atol=1e-9)
    assert energy(apart, [0, 1], label_cost=10_000.0) == pytest.approx(20_000.0)


def test_circle_of_four_is_one_group():
    angle = np.arange(4) * math.pi / 2
    position = 0.7 * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    # Everyone faces the centre, so every segment point is the centre: zero distance cost.
    assert groups_of(position, angle + math.pi) == {frozenset(range(4))}


def test_two_separate_groups():
    position = [[0.0, 0.0], [1.2, 0.0], [5.0, 3.0], [5.0, 4.2]]
    yaw = [0.0, math.pi, math.pi / 2, -math.pi / 2]
    assert groups_of(position, yaw) == {frozenset({0, 1}), frozenset({2, 3})}


def test_person_behind_another_is_kept_out_by_the_visibility_penalty(monkeypatch):
    # A (0, 0) and B (1.2 m, 0) face each other: centre (60, 0) cm. C stands behind B at
    # (210, 10) cm, facing that centre; its segment point is 80 cm from it (6,453 cm² < mdl),
    # so on distance alone C would join. Seen from the centre, C is behind B:
    # cos * r_C / r_B = (v_B . v_C) / r_B^2 = (60*150) / 60^2 = 2.5, a penalty of 100^2.5 = 1e5.
    position_cm = np.array([[0.0, 0.0], [120.0, 0.0], [210.0, 10.0]])
    yaw = np.array([0.0, math.pi, math.atan2(-10.0, 60.0 - 210.0)])
    points = segment_points(position_cm, yaw, stride=70.0)
    costs = unary_costs(points, position_cm, np.array([0, 0, 1]), mdl=10_000.0)
    distance = float(np.sum((points[2] - [60.0, 0.0]) ** 2))
    assert distance == pytest.approx(6_453.0, abs=1.0)
    assert costs[2, 0] == pytest.approx(distance + 1e5)
    assert groups_of(position_cm / 100, yaw) == {frozenset({0, 1}), frozenset({2})}
    # With the penalty switched off (a cosine threshold no pair can pass), C joins.
    monkeypatch.setattr(gcff_module, "VISIBILITY_COSINE", 1.1)
    assert groups_of(position_cm / 100, yaw) == {frozenset({0, 1, 2})}


def test_everyone_facing_away_stays_alone():
    angle = np.arange(4) * math.pi / 2
    position = 0.7 * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    assert groups_of(position, angle) == {frozenset({i}) for i in range(4)}


def test_someone_on_a_centre_gives_finite_costs():
    # Persons 0 and 2 face each other: segment points (35, 0) and (65, 0) cm, centre (50, 0).
    # Person 1 stands 1e-9 cm from that centre, so person 2 is "behind" them with
    # cos * r_2 / r_1 = 50 / 1e-9: 100 ** 5e10 would overflow; the exponent is capped.
    position_cm = np.array([[0.0, 0.0], [50.0 + 1e-9, 0.0], [100.0, 0.0]])
    yaw = np.array([0.0, math.pi / 2, math.pi])
    points = segment_points(position_cm, yaw, stride=35.0)
    costs = unary_costs(points, position_cm, np.array([0, 1, 0]), mdl=1e6)
    assert np.all(np.isfinite(costs))
    cap = gcff_module.VISIBILITY_BASE**gcff_module.MAX_VISIBILITY_EXPONENT
    assert costs[2, 0] == pytest.approx(cap)  # 225 cm² of distance vanish beside 1e200
    assert costs[0, 0] == pytest.approx(225.0)  # person 0 is in front: no penalty
    # The run ends with everyone in one group, centred at (50, 11.7) cm: 1e6 cm² of label cost
    # plus ~1,267 cm² of distances, and nobody hides anyone from there (cosines 0.23 and < 0);
    # any split costs at least one more label, 1e6 cm².
    labels = gcff_labels(position_cm, yaw, stride=35.0, mdl=1e6, units="cm")
    assert label_sets(labels) == {frozenset({0, 1, 2})}


def test_empty_and_single_person_frames():
    assert gcff_labels(np.zeros((0, 2)), np.zeros(0), stride=0.7, mdl=1.0).shape == (0,)
    assert gcff_labels([[1.0, 2.0]], [0.3], stride=0.7, mdl=1.0).tolist() == [0]
    frame = Frame(ids=[7], position=[[0.0, 0.0]], yaw=[0.0])
    assert Gcff().predict([frame]) == [((7,),)]


# ---------------------------------------------------------------------------------------------
# Invariants
# ---------------------------------------------------------------------------------------------


def scenes():
    """Random scenes of 1-12 people within a 6 m square (metres, radians)."""
    return st.integers(min_value=1, max_value=12).flatmap(
        lambda n: st.tuples(
            st.lists(st.tuples(st.floats(0, 6), st.floats(0, 6)), min_size=n, max_size=n).map(
                np.array
            ),
            st.lists(st.floats(-math.pi, math.pi), min_size=n, max_size=n).map(np.array),
        )
    )


@settings(max_examples=60, deadline=None)
@given(scenes())
def test_output_is_a_partition_and_energy_never_increases(scene):
    position, yaw = scene
    ids = np.arange(100, 100 + len(yaw))
    frame = Frame(ids=ids, position=position, yaw=yaw)
    (partition,) = Gcff().predict([frame])
    members = [m for group in partition for m in group]
    assert sorted(members) == ids.tolist()
    # Within every expansion, accepted moves never raise the energy.
    position_cm = position * 100
    points = segment_points(position_cm, yaw, stride=70.0)
    labels = np.arange(len(yaw))
    for _ in range(gcff_module.MAX_REFITS):
        costs = unary_costs(points, position_cm, labels, mdl=10_000.0)
        result = alpha_expansion(costs, labels, label_cost=10_000.0)
        assert all(b <= a for a, b in zip(result.energies, result.energies[1:], strict=False))
        assert result.energies[-1] == energy(costs, result.labels, label_cost=10_000.0)
        _, renumbered = np.unique(result.labels, return_inverse=True)
        if np.array_equal(renumbered, labels):
            break
        labels = renumbered


def singleton_costs(frame, *, stride_cm: float, mdl_cm2: float):
    """A frame's unary costs (centimetres) with everyone their own label, and those labels."""
    position_cm = frame.position * 100
    points = segment_points(position_cm, frame.yaw, stride=stride_cm)
    labels = np.arange(frame.n_people)
    return unary_costs(points, position_cm, labels, mdl=mdl_cm2), labels


def test_energy_never_increases_on_salsa(salsa_frames):
    for frame in salsa_frames[::50]:
        costs, labels = singleton_costs(frame, stride_cm=70.0, mdl_cm2=10_000.0)
        result = alpha_expansion(costs, labels, label_cost=10_000.0)
        assert len(result.energies) > 1  # singletons always merge on SALSA
        assert np.all(np.diff(result.energies) <= 0)


def sequential_expansion(costs, labels, cost):
    """Spec, step 4, one alpha-move at a time with a loop over labels."""
    n, k = costs.shape
    current = energy(costs, labels, label_cost=cost)
    alpha, stale = 0, 0
    while stale < k:
        d = costs[:, alpha] - costs[np.arange(n), labels]
        new = labels.copy()
        for label in np.unique(labels):
            if label == alpha:
                continue
            members = labels == label
            option_a = d[members & (d < 0)].sum() + cost
            option_b = d[members].sum()
            new[members & ((option_b <= option_a) | (d <= 0))] = alpha
        candidate = energy(costs, new, label_cost=cost)
        if candidate < current:
            labels, current, stale = new, candidate, 0
        else:
            if candidate == current:
                labels = new
            stale += 1
        alpha = (alpha + 1) % k
    return labels


def test_alpha_expansion_matches_one_move_at_a_time(salsa_frames):
    """The windowed, vectorised sweep equals the plain sequential one (spec, step 4)."""
    for frame in salsa_frames[::40]:
        costs, labels = singleton_costs(frame, stride_cm=50.0, mdl_cm2=20_000.0)
        fast = alpha_expansion(costs, labels, label_cost=20_000.0).labels
        np.testing.assert_array_equal(fast, sequential_expansion(costs, labels, 20_000.0))


@pytest.mark.parametrize("n", [40, 90])
def test_alpha_expansion_matches_one_move_at_a_time_in_crowds(n):
    """Crowds take the windowed path (K > 32) and, beyond 64 people, sorted per-label sums."""
    rng = np.random.default_rng(n)
    position_cm = rng.uniform(0.0, 100.0 * math.sqrt(n), size=(n, 2))
    yaw = rng.uniform(-math.pi, math.pi, n)
    points = segment_points(position_cm, yaw, stride=70.0)
    labels = np.arange(n)
    for _ in range(3):  # the first expansions of a run: from singletons, then refitted
        costs = unary_costs(points, position_cm, labels, mdl=10_000.0)
        fast = alpha_expansion(costs, labels, label_cost=10_000.0).labels
        np.testing.assert_array_equal(fast, sequential_expansion(costs, labels, 10_000.0))
        _, labels = np.unique(fast, return_inverse=True)


def test_relabelling_ids_renames_the_groups(salsa_frames):
    detector = Gcff()
    for frame in salsa_frames[::25]:
        renamed = frame.replace(ids=frame.ids * 7 + 1000, groups=None)
        (original,) = detector.predict([frame])
        (result,) = detector.predict([renamed])
        assert as_sets(result) == as_sets(tuple(tuple(m * 7 + 1000 for m in g) for g in original))


@pytest.mark.parametrize("angle", [math.pi / 2, 0.5, -2.0])
def test_rotation_invariance_on_salsa(salsa_frames, angle):
    c, s = math.cos(angle), math.sin(angle)
    rotation = np.array([[c, -s], [s, c]])
    detector = Gcff()
    frames = salsa_frames[::5]
    rotated = [
        f.replace(
            position=f.position @ rotation.T,
            yaw=(f.yaw + angle + math.pi) % (2 * math.pi) - math.pi,
        )
        for f in frames
    ]
    before = detector.predict(frames)
    after = detector.predict(rotated)
    assert [as_sets(p) for p in after] == [as_sets(p) for p in before]


def test_translation_invariance_on_salsa(salsa_frames):
    # Exact in real arithmetic. In floating point, a move that swaps the two labels of a pair
    # changes the energy by exactly zero, and rounding decides whether the sweep counts it as a
    # decrease (as in the reference code); a shift of the origin can flip that call, and rarely
    # the answer: 1 of 1,143 SALSA frames for a shift of (3, -2) m, none for (2.5, -1.25) m.
    detector = Gcff()
    before = detector.predict(salsa_frames)
    for shift in ([2.5, -1.25], [3.0, -2.0], [-40.0, 25.0]):
        moved = [f.replace(position=f.position + shift) for f in salsa_frames]
        after = detector.predict(moved)
        differ = sum(as_sets(a) != as_sets(b) for a, b in zip(after, before, strict=True))
        assert differ <= 2, f"shift {shift}: {differ} frames differ"


def test_translation_invariance_on_hand_scenes():
    position = np.array([[0.0, 0.0], [1.2, 0.0], [2.1, 0.1], [5.0, 3.0], [5.0, 4.2]])
    yaw = np.array([0.0, math.pi, math.atan2(-0.1, -1.5), math.pi / 2, -math.pi / 2])
    base = groups_of(position, yaw)
    for shift in ([100.0, -250.0], [-3.3, 7.7]):
        assert groups_of(position + shift, yaw) == base


# ---------------------------------------------------------------------------------------------
# Units
# ---------------------------------------------------------------------------------------------


def test_metres_and_centimetres_give_identical_groups(salsa_frames):
    for frame in salsa_frames[::20]:
        in_m = gcff_labels(frame.position, frame.yaw, stride=0.7, mdl=1.0, units="m")
        in_cm = gcff_labels(frame.position * 100, frame.yaw, stride=70.0, mdl=10_000.0, units="cm")
        np.testing.assert_array_equal(in_m, in_cm)


def test_naive_metres_are_not_gcff(salsa_frames):
    """The visibility penalty is not scale-free: reading metre data as if it were centimetres
    (stride 0.7, mdl 1) is a different detector, and a much worse one."""
    frames = salsa_frames[::10]
    naive = [gcff_labels(f.position, f.yaw, stride=0.7, mdl=1.0, units="cm") for f in frames]
    proper = [gcff_labels(f.position, f.yaw, stride=0.7, mdl=1.0, units="m") for f in frames]
    assert sum(label_sets(a) != label_sets(b) for a, b in zip(naive, proper, strict=True)) > 10


def test_settings_in_centimetres_convert_exactly():
    detector = Gcff.from_settings(stride=70, mdl=10_000, units="cm", orientation="head")
    assert detector.get_params()["stride"] == 0.7
    assert detector.get_params()["mdl"] == 1.0
    assert detector.get_params()["orientation"] == "head"
    paper = Gcff.from_settings(stride=70, mdl=30_000, units="cm")
    assert (paper.stride, paper.mdl) == (0.7, 3.0)
    same = Gcff.from_settings(stride=0.7, mdl=3.0, units="m")
    assert (same.stride, same.mdl) == (0.7, 3.0)


def test_metre_parameters_reach_the_reference_centimetres_exactly():
    # 0.7 * 100 is 70.00000000000001 in binary floating point; the conversion goes through the
    # decimal the user wrote, so the reference's 70 cm is used exactly.
    assert gcff_module._convert(0.7, 100.0) == 70.0
    assert gcff_module._convert(1.5, 10_000.0) == 15_000.0


# ---------------------------------------------------------------------------------------------
# Estimator interface, tuning, errors
# ---------------------------------------------------------------------------------------------


def test_estimator_interface(salsa_frames):
    detector = Gcff(stride=0.6, mdl=1.5)
    assert detector.get_params()["stride"] == 0.6
    copy = clone(detector).set_params(mdl=2.0)
    assert (copy.stride, copy.mdl) == (0.6, 2.0)
    assert detector.fit(salsa_frames[:3]) is detector
    assert (detector.stride_, detector.mdl_, detector.grid_search_) == (0.6, 1.5, None)
    # No training needed without tuning: a fresh instance predicts.
    assert Gcff().predict(salsa_frames[:2]) == Gcff().fit([]).predict(salsa_frames[:2])


def test_tuning_picks_the_best_setting_on_training_frames_only(salsa_frames):
    train, test = salsa_frames[:400:8], salsa_frames[400::8]
    detector = Gcff(tune=True, stride_grid=(0.5, 0.7), mdl_grid=(0.5, 1.0, 3.0))
    with pytest.raises(NotFittedError, match="fitted on training frames"):
        detector.predict(test)
    detector.fit(train)
    search = detector.grid_search_
    assert search.f1.shape == (6,) and search.n_frames == len(train)
    assert search.best == int(np.argmax(search.f1))
    assert (detector.stride_, detector.mdl_) == (search.best_stride, search.best_mdl)
    fixed = Gcff(stride=search.best_stride, mdl=search.best_mdl)
    best_f1 = evaluate(train, fixed.predict(train)).at(T_TWO_THIRDS).f1
    assert search.best_f1 == pytest.approx(best_f1)
    assert detector.predict(test) == fixed.predict(test)
    again = grid_search(train, stride_grid=(0.5, 0.7), mdl_grid=(0.5, 1.0, 3.0))
    np.testing.assert_array_equal(again.f1, search.f1)


def test_head_orientation(salsa_frames):
    frames = salsa_frames[::30]
    head = Gcff(orientation="head").predict(frames)
    body = Gcff(orientation="body").predict(frames)
    assert any(as_sets(h) != as_sets(b) for h, b in zip(head, body, strict=True))
    manual = [label_sets(gcff_labels(f.position, f.head_yaw, stride=0.7, mdl=1.0)) for f in frames]
    assert [
        frozenset(frozenset(f.index_of(m) for m in g) for g in p)
        for f, p in zip(frames, head, strict=True)
    ] == manual
    no_head = Frame(ids=[1, 2], position=[[0, 0], [1, 0]], yaw=[0, math.pi])
    with pytest.raises(ValueError, match="orientation='head' needs head yaws"):
        Gcff(orientation="head").predict([no_head])


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"orientation": "gaze"}, "orientation must be one of"),
        ({"mdl": 0.0}, r"mdl must be a finite number > 0 and <= 1e\+16, got 0.0"),
        ({"stride": -0.1}, "stride must be a finite number >= 0"),
        ({"mdl": float("nan")}, "mdl must be a finite number > 0"),
        ({"stride": 1e300}, r"stride must be a finite number >= 0 and <= 1e\+08, got 1e\+300"),
    ],
)
def test_bad_parameters_are_named(params, match):
    frame = Frame(ids=[1, 2], position=[[0, 0], [1, 0]], yaw=[0, math.pi])
    with pytest.raises(ValueError, match=match):
        Gcff(**params).fit([frame])
    with pytest.raises(ValueError, match=match):
        Gcff(**params).predict([frame])


def test_settings_file_errors_name_the_file(tmp_path):
    with pytest.raises(
        DataFormatError, match=r"nope.mat: expected a MATLAB .mat file, found no such file"
    ):
        Gcff.from_settings_file(tmp_path / "nope.mat")
    scipy.io.savemat(tmp_path / "settings_gc.mat", {"stride": -70.0, "mdl": 10000.0})
    with pytest.raises(
        DataFormatError,
        match=r"settings_gc.mat: field 'stride': expected a finite length >= 0 .*found -70.0",
    ):
        Gcff.from_settings_file(tmp_path / "settings_gc.mat")
    scipy.io.savemat(tmp_path / "settings_gc.mat", {"stride": 70.0, "mdl": 10000.0})
    detector = Gcff.from_settings_file(tmp_path / "settings_gc.mat")
    assert (detector.stride, detector.mdl) == (0.7, 1.0)


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="units must be one of"):
        gcff_labels([[0.0, 0.0]], [0.0], stride=0.7, mdl=1.0, units="mm")
    with pytest.raises(ValueError, match=r"yaw must have shape \(2,\), got \(3,\)"):
        gcff_labels([[0.0, 0.0], [1.0, 0.0]], [0.0, 1.0, 2.0], stride=0.7, mdl=1.0)
    with pytest.raises(ValueError, match="unary must be finite"):
        alpha_expansion([[0.0, np.inf]], [0], label_cost=1.0)
    with pytest.raises(ValueError, match="label_cost must be a finite number >= 0, got -1.0"):
        alpha_expansion([[0.0, 1.0]], [0], label_cost=-1.0)
    with pytest.raises(TypeError, match=r"frames\[0\] must be a reform.Frame"):
        Gcff().predict([object()])
    with pytest.raises(ValueError, match="annotated frames to tune on"):
        Gcff(tune=True).fit([Frame(ids=[1], position=[[0, 0]], yaw=[0])])

"""REFORM on crowds (frames of more than ``LARGE_FRAME_PEOPLE``): the same partition as
classifying every pair and reconstructing the whole Relation Matrix, on synthetic and real
(SALSA) frames, with memory that does not grow with the square of the people."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from toy_scenes import toy_frames
from traced import traced_peak

import reform.detector
from reform import (
    Frame,
    Reform,
    frame_pair_features,
    greedy_reconstruction,
    partition_from_labels,
    relation_matrix,
    time_split,
)
from reform.classifiers import CLASSIFIERS, make_classifier
from reform.detector import LARGE_FRAME_PEOPLE
from reform.fast import sklearn_pair_labels
from reform.features import pair_indices
from reform.reconstruction import graph_greedy_labels


def tiled(frames: list[Frame], *, spacing_m: float, seed: int) -> Frame:
    """One crowd of ``frames`` side by side on a grid ``spacing_m`` apart, ids shuffled."""
    side = int(np.ceil(np.sqrt(len(frames))))
    position = np.concatenate(
        [
            f.position + spacing_m * np.array([k % side, k // side], dtype=float)
            for k, f in enumerate(frames)
        ]
    )
    yaw = np.concatenate([f.yaw for f in frames])
    n = yaw.size
    ids = np.random.default_rng(seed).permutation(np.arange(100, 100 + 7 * n, 7))
    return Frame(ids=ids, position=position, yaw=yaw)


def every_pair(model: Reform, frame: Frame, *, whole_matrix: bool = False):
    """The reference: every pair classified by the scikit-learn classifier itself, then Greedy
    Reconstruction (the whole-matrix reference with ``whole_matrix``)."""
    order = np.argsort(frame.ids)
    ordered = Frame(ids=frame.ids[order], position=frame.position[order], yaw=frame.yaw[order])
    x = frame_pair_features(ordered, features=model.features_)
    labels = sklearn_pair_labels(model.classifier_, x, threshold=model.threshold)
    n = ordered.n_people
    if whole_matrix:
        rows = greedy_reconstruction(relation_matrix(labels, n), variant=model.reconstruction)
    else:
        i, j = pair_indices(n)
        pairs = np.flatnonzero(labels)
        rows = partition_from_labels(
            graph_greedy_labels(n, i[pairs], j[pairs], variant=model.reconstruction), range(n)
        )
    return tuple(sorted((tuple(int(ordered.ids[r]) for r in g) for g in rows), key=min))


@functools.cache
def toy_model(name: str, **options) -> Reform:
    return Reform(make_classifier(name), **options).fit(toy_frames(0, 120))


@functools.cache
def toy_crowd(seed: int, spacing_m: float, scenes: int = 36) -> Frame:
    parts = toy_frames(seed, scenes, sizes=(2, 5, 3, 4), loners=4)  # 18 people each
    return tiled(parts, spacing_m=spacing_m, seed=seed)


@pytest.mark.parametrize("name", list(CLASSIFIERS))
@pytest.mark.parametrize(
    "options",
    [{}, {"reconstruction": "intersection"}, {"features": "relative"}],
    ids=["paper", "intersection", "relative"],
)
def test_a_crowd_gets_the_partition_of_every_pair_classified(name, options):
    # Tiles 5 m apart: people of neighbouring tiles are close enough to be paired.
    frame = toy_crowd(11, 5.0)
    assert frame.n_people > LARGE_FRAME_PEOPLE
    model = toy_model(name, **options)
    assert model.predict([frame])[0] == every_pair(model, frame)


def test_the_default_table_classifies_only_the_pairs_near_enough():
    # The crowd tests above run the k-d tree search: the toy model's table knows a distance
    # from which every pair is apart (a table on Distance and Effort Angle, reform.fast).
    apart = toy_model("bagged-trees")._pair_classifier().apart_from(0)
    assert apart is not None and 0 < apart < 5.0


@pytest.mark.parametrize("options", [{}, {"features": "relative"}], ids=["near", "all-pairs"])
def test_a_crowd_classified_a_few_pairs_at_a_time(monkeypatch, options):
    frame = toy_crowd(17, 4.0, scenes=20)
    model = toy_model("bagged-trees", **options)
    expected = every_pair(model, frame)
    monkeypatch.setattr(reform.detector, "CHUNK_PAIRS", 1_000)
    assert model.predict([frame])[0] == expected


@pytest.mark.parametrize(
    ("name", "threshold"), [("bagged-trees", 0.3), ("logistic-regression", 0.7)]
)
def test_a_crowd_with_a_threshold(name, threshold):
    frame = toy_crowd(12, 4.0)
    model = toy_model(name, threshold=threshold)
    assert model.predict([frame])[0] == every_pair(model, frame)


def test_a_crowd_without_the_compiled_classifier():
    frame = toy_crowd(13, 4.5)
    model = toy_model("bagged-trees", fast=False)
    assert model.predict([frame])[0] == every_pair(model, frame)


def test_a_crowd_against_the_whole_matrix_reconstruction():
    frame = toy_crowd(14, 3.5, scenes=16)  # 288 people, tiles overlapping
    model = toy_model("bagged-trees")
    assert model.predict([frame])[0] == every_pair(model, frame, whole_matrix=True)


def test_a_crowd_of_far_apart_scenes_is_each_scene_predicted_alone():
    # Frames 100 m apart share no pair: the crowd's groups are each frame's own, predicted
    # through the path for small frames.
    parts = toy_frames(15, 20, sizes=(2, 5, 3, 4), loners=4)
    frame = tiled(parts, spacing_m=100.0, seed=15)
    model = toy_model("bagged-trees")
    ids = np.split(frame.ids, np.cumsum([f.n_people for f in parts])[:-1])
    alone = model.predict([f.replace(ids=k, groups=None) for f, k in zip(parts, ids, strict=True)])
    expected = tuple(sorted((g for p in alone for g in p), key=min))
    assert model.predict([frame])[0] == expected


@pytest.mark.parametrize(
    ("options", "bound_mb"),
    [({}, 20), ({"features": "relative"}, 64)],
    ids=["near-pairs", "every-pair-by-chunks"],
)
def test_a_crowd_takes_memory_in_proportion_to_its_people(options, bound_mb):
    # 3,600 people: classifying every pair at once would take 6.5 million pairs * 40 bytes,
    # 260 MB. The crowd path classifies the pairs near enough to be together (about 1 MB
    # measured), or every pair a chunk at a time (about 28 MB measured: a chunk's features).
    frame = tiled(toy_frames(16, 200, sizes=(2, 5, 3, 4), loners=4), spacing_m=6.0, seed=16)
    model = toy_model("bagged-trees", **options)
    model.predict([frame])  # compiled already; this warms the k-d tree code
    partition, peak = traced_peak(lambda: model.predict([frame])[0])
    assert sorted(k for g in partition for k in g) == sorted(frame.ids.tolist())
    assert peak < bound_mb * 2**20, f"peak {peak / 2**20:.1f} MiB"


@pytest.fixture(scope="module")
def salsa_model(salsa_dataset) -> tuple[Reform, tuple[Frame, ...]]:
    train, test = time_split(salsa_dataset.annotated())
    return Reform().fit(train), test


@pytest.mark.parametrize("spacing_m", [4.0, 8.0], ids=["overlapping", "side-by-side"])
def test_real_frames_tiled_into_a_crowd(salsa_model, spacing_m):
    # SALSA's test frames (18 people each, as recorded) side by side: 360 people per crowd.
    model, test = salsa_model
    for start in (0, len(test) // 2):
        frame = tiled(list(test[start : start + 20]), spacing_m=spacing_m, seed=start)
        assert model.predict([frame])[0] == every_pair(model, frame)


def test_real_frames_far_apart_are_predicted_as_alone(salsa_model):
    model, test = salsa_model
    parts = list(test[:: max(1, len(test) // 20)][:20])
    frame = tiled(parts, spacing_m=100.0, seed=1)
    ids = np.split(frame.ids, np.cumsum([f.n_people for f in parts])[:-1])
    alone = model.predict([f.replace(ids=k, groups=None) for f, k in zip(parts, ids, strict=True)])
    assert model.predict([frame])[0] == tuple(sorted((g for p in alone for g in p), key=min))

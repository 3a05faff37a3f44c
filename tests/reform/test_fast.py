"""Compiled pair classifiers give exactly the scikit-learn classifier's labels."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.ensemble import BaggingClassifier, ExtraTreesClassifier, RandomForestClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.naive_bayes import GaussianNB
from sklearn.neighbors import KNeighborsClassifier
from sklearn.tree import DecisionTreeClassifier
from toy_scenes import toy_frames

from reform.classifiers import bagged_trees, logistic_regression, weighted_knn
from reform.detector import COMPILE_AFTER_S, Reform
from reform.fast import compile_classifier, sklearn_pair_labels


def pair_data(seed: int, n: int = 4000) -> tuple[np.ndarray, np.ndarray]:
    """Distance-and-angle-like features with a noisy 'close and facing' rule."""
    rng = np.random.default_rng(seed)
    x = np.column_stack([rng.gamma(2.0, 1.5, n), rng.uniform(0, 2 * np.pi, n)])
    y = ((x[:, 0] < 2.0) & (x[:, 1] < 2.5)) ^ (rng.random(n) < 0.08)
    return x, y.astype(int)


def queries(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x, _ = pair_data(seed + 1, 10000)
    wide = np.column_stack([rng.uniform(-1, 30, 5000), rng.uniform(-1, 7, 5000)])
    return np.concatenate([x, wide, [[0.0, 0.0], [-0.0, -0.0], [1e30, 1e30]]])


CLASSIFIERS = {
    "bagged-trees": lambda: bagged_trees(min_samples_leaf=15),
    "bagged-trees-pure": lambda: bagged_trees(n_estimators=8, min_samples_leaf=1),
    "bagged-feature-subsets": lambda: BaggingClassifier(
        DecisionTreeClassifier(), n_estimators=10, max_features=1, random_state=1
    ),
    "random-forest": lambda: RandomForestClassifier(
        n_estimators=12, min_samples_leaf=3, random_state=0
    ),
    "extra-trees": lambda: ExtraTreesClassifier(n_estimators=4, min_samples_leaf=4, random_state=0),
    "one-tree": lambda: DecisionTreeClassifier(min_samples_leaf=2, random_state=0),
    "weighted-knn": lambda: weighted_knn(n_neighbors=15),
    "uniform-knn": lambda: KNeighborsClassifier(n_neighbors=4),
    "logistic-regression": logistic_regression,
    "bare-logistic": lambda: LogisticRegression(C=0.3),
    "naive-bayes": GaussianNB,
}


@pytest.mark.parametrize("name", list(CLASSIFIERS))
@pytest.mark.parametrize("threshold", [None, 0.25, 0.5])
def test_compiled_labels_equal_scikit_learn(name, threshold):
    x, y = pair_data(0)
    classifier = CLASSIFIERS[name]().fit(x, y)
    compiled = compile_classifier(classifier, threshold=threshold)
    assert compiled.exact
    q = queries(1)
    expected = sklearn_pair_labels(classifier, q, threshold=threshold)
    assert np.array_equal(compiled.predict(q), expected)
    assert compiled.predict(q[:0]).shape == (0,)


def test_tree_ensembles_compile_to_a_table_or_fall_back_to_apply():
    x, y = pair_data(2)
    classifier = bagged_trees(min_samples_leaf=20).fit(x, y)
    table = compile_classifier(classifier)
    assert table.kind == "tree-table"
    fallback = compile_classifier(classifier, max_cells=100)
    assert fallback.kind == "tree-apply"
    q = queries(3)
    assert np.array_equal(table.predict(q), fallback.predict(q))
    assert np.array_equal(table.predict(q), classifier.predict(q) == 1)


def test_three_features_use_apply():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(3000, 3))
    y = (x.sum(axis=1) > 0).astype(int)
    classifier = bagged_trees(n_estimators=5, min_samples_leaf=5).fit(x, y)
    compiled = compile_classifier(classifier)
    assert compiled.kind == "tree-apply"
    q = rng.normal(size=(5000, 3))
    assert np.array_equal(compiled.predict(q), classifier.predict(q) == 1)


def test_kinds():
    x, y = pair_data(4, 2000)
    assert compile_classifier(weighted_knn().fit(x, y)).kind == "neighbors"
    assert compile_classifier(logistic_regression().fit(x, y)).kind == "linear"
    assert compile_classifier(GaussianNB().fit(x, y)).kind == "sklearn"


def test_ties_are_settled_as_scikit_learn_settles_them():
    # Two pure trees that disagree on half the plane: a 1-1 vote, which argmax gives to class 0.
    x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]] * 10)
    y = np.array([0, 1, 1, 1] * 10)
    classifier = BaggingClassifier(
        DecisionTreeClassifier(), n_estimators=2, max_features=1, bootstrap=False, random_state=0
    ).fit(x, y)
    grid = np.array([[a, b] for a in (-1, 0, 0.5, 1, 2) for b in (-1, 0, 0.5, 1, 2)], dtype=float)
    for threshold in (None, 0.5, 0.75):
        expected = sklearn_pair_labels(classifier, grid, threshold=threshold)
        assert np.array_equal(
            compile_classifier(classifier, threshold=threshold).predict(grid), expected
        )


@pytest.mark.parametrize("name", [k for k in CLASSIFIERS if "trees" in k or "forest" in k])
@pytest.mark.parametrize("threshold", [None, 0.5])
def test_a_table_knows_the_distance_from_which_every_pair_is_apart(name, threshold):
    # Features at or above `apart_from(0)`, whatever the second, are apart for the classifier
    # itself; just below it, the table says together somewhere (its own edge, not a guess).
    x, y = pair_data(0)
    y[x[:, 0] > 6.0] = 0  # no pair far apart is together in the training data
    classifier = CLASSIFIERS[name]().fit(x, y)
    compiled = compile_classifier(classifier, threshold=threshold)
    apart = compiled.apart_from(0)
    assert apart is not None and 0 < apart <= 6.0 + 1e-6
    step = np.float32(apart)
    first = np.array([apart, float(np.nextafter(step, np.float32(np.inf))), apart * 1.01, 7, 1e30])
    second = np.concatenate([np.linspace(-1, 7, 801), x[:, 1]])
    grid = np.column_stack([np.repeat(first, second.size), np.tile(second, first.size)])
    assert not sklearn_pair_labels(classifier, grid, threshold=threshold).any()


def test_only_a_table_knows_a_distance_from_which_every_pair_is_apart():
    x, y = pair_data(4, 2000)
    for classifier in (weighted_knn(), logistic_regression(), GaussianNB()):
        assert compile_classifier(classifier.fit(x, y)).apart_from(0) is None
    # A table whose highest distances still say together somewhere knows none.
    y_far = y.copy()
    y_far[x[:, 0] > 8.0] = 1
    trees = bagged_trees(min_samples_leaf=5).fit(x, y_far)
    assert compile_classifier(trees).apart_from(0) is None


def test_a_detector_compiles_its_classifier_once_it_pays():
    model = Reform(bagged_trees()).fit(toy_frames(0, 30))
    few = toy_frames(5, 4)
    first = model.predict(few)  # a short run: scikit-learn's own classifier
    assert model._compiled is None
    for _ in range(10_000):  # a stream of frames: compiled once it has cost COMPILE_AFTER_S
        model.predict(few[:1])
        if model._compiled is not None:
            break
    assert model._compiled is not None
    assert model._sklearn_s >= COMPILE_AFTER_S
    assert model.predict(few) == first  # the compiled table gives the same groups
    plain = Reform(bagged_trees(), fast=False).fit(toy_frames(0, 30))
    assert plain.compile()._compiled is None

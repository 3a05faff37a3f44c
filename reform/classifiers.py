"""The paper's three ready-made pair classifiers, and the grids their hyper-parameters are tuned on.

REFORM takes any scikit-learn classifier; these are the three the paper compares, each in the
category it stands for:

* ``"weighted-knn"`` — k-nearest neighbours weighted by inverse distance, on standardised
  features (as MATLAB's "Weighted KNN" preset, which the paper's names follow, standardises).
* ``"bagged-trees"`` — bagging of decision trees (30, as MATLAB's "Bagged Trees" preset).
  MATLAB grows each tree to purity, which memorises the training pairs; here leaves hold at
  least ``min_samples_leaf`` pairs (default 50: on SALSA's training part, time-blocked
  cross-validation scores 25 to 400 within 0.2 points of each other, see
  ``docs/results/paper-experiment.md``), which compiles to an exact lookup table
  (:mod:`reform.fast`).
* ``"logistic-regression"`` — logistic regression on standardised features.

:data:`PARAM_GRIDS` holds, per classifier, the grid :func:`reform.tuning.tune` searches with
cross-validation on training frames only.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

WEIGHTED_KNN = "weighted-knn"
BAGGED_TREES = "bagged-trees"
LOGISTIC_REGRESSION = "logistic-regression"

DEFAULT_N_NEIGHBORS = 10  # neighbours (MATLAB "Weighted KNN" preset)
DEFAULT_N_TREES = 30  # trees (MATLAB "Bagged Trees" preset)
DEFAULT_MIN_SAMPLES_LEAF = 50  # pairs per leaf
DEFAULT_C = 1.0  # inverse L2 regularisation strength
DEFAULT_RANDOM_STATE = 0

__all__ = [
    "BAGGED_TREES",
    "CLASSIFIERS",
    "LOGISTIC_REGRESSION",
    "PARAM_GRIDS",
    "WEIGHTED_KNN",
    "bagged_trees",
    "logistic_regression",
    "make_classifier",
    "weighted_knn",
]


def weighted_knn(*, n_neighbors: int = DEFAULT_N_NEIGHBORS) -> Any:
    """Distance-weighted k-nearest neighbours on standardised features.

    Args:
        n_neighbors: neighbours consulted per pair.

    Returns:
        An unfitted ``Pipeline(StandardScaler, KNeighborsClassifier(weights="distance"))``.
    """
    from sklearn.neighbors import KNeighborsClassifier
    from sklearn.pipeline import Pipeline
    from sklearn.preprocessing import StandardScaler

    return Pipeline(
        [
            ("scale", StandardScaler()),
            ("knn", KNeighborsClassifier(n_neighbors=n_neighbors, weights="distance")),
        ]
    )


def bagged_trees(
    *,
    n_estimators: int = DEFAULT_N_TREES,
    min_samples_leaf: int = DEFAULT_MIN_SAMPLES_LEAF,
    random_state: int = DEFAULT_RANDOM_STATE,
) -> Any:
    """Bagging of decision trees.

    Args:
        n_estimators: number of trees.
        min_samples_leaf: fewest training pairs in a leaf (1 grows trees to purity).
        random_state: seed of the bootstrap samples.

    Returns:
        An unfitted ``BaggingClassifier(DecisionTreeClassifier(...))``.
    """
    from sklearn.ensemble import BaggingClassifier
    from sklearn.tree import DecisionTreeClassifier

    return BaggingClassifier(
        DecisionTreeClassifier(min_samples_leaf=min_samples_leaf),
        n_estimators=n_estimators,
        random_state=random_state,
    )


def logistic_regression(*, C: float = DEFAULT_C) -> Any:  # noqa: N803 (scikit-learn's name)
    """Logistic regression on standardised features.

    Args:
        C: inverse L2 regularisation strength.

    Returns:
        An unfitted ``Pipeline(StandardScaler, LogisticRegression)``.
    """
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import Pipeline
    from sklearn.preprocessing import StandardScaler

    return Pipeline([("scale", StandardScaler()), ("logreg", LogisticRegression(C=C))])


CLASSIFIERS: Mapping[str, Callable[..., Any]] = MappingProxyType(
    {
        WEIGHTED_KNN: weighted_knn,
        BAGGED_TREES: bagged_trees,
        LOGISTIC_REGRESSION: logistic_regression,
    }
)

# Hyper-parameter grids for cross-validation, in the classifiers' own parameter names.
PARAM_GRIDS: Mapping[str, Mapping[str, tuple[Any, ...]]] = MappingProxyType(
    {
        WEIGHTED_KNN: MappingProxyType({"knn__n_neighbors": (10, 25, 50, 100, 200, 400)}),
        BAGGED_TREES: MappingProxyType(
            {"estimator__min_samples_leaf": (10, 25, 50, 100, 200, 400)}
        ),
        LOGISTIC_REGRESSION: MappingProxyType({"logreg__C": (0.01, 0.1, 1.0, 10.0, 100.0)}),
    }
)


def make_classifier(name: str, **params: Any) -> Any:
    """A ready-made classifier by name.

    Args:
        name: one of :data:`CLASSIFIERS`.
        **params: keyword arguments of its factory.

    Raises:
        ValueError: for an unknown name.
    """
    if name not in CLASSIFIERS:
        raise ValueError(f"classifier must be one of {tuple(CLASSIFIERS)}, got {name!r}")
    return CLASSIFIERS[name](**params)

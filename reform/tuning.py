"""Hyper-parameters of REFORM's classifiers chosen by time-blocked cross-validation.

:func:`tune` scores a grid of settings of a ready-made classifier
(:data:`reform.classifiers.PARAM_GRIDS`) on the pairs of training frames, with folds that are
stretches of time (:func:`reform.time_blocks`, ``GroupKFold``), so that a fold never tests on
the neighbours of frames it trained on; :func:`classifier_params` turns the chosen grid
setting into keywords of the ready-made factory (:func:`reform.classifiers.make_classifier`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from sklearn.model_selection import GridSearchCV, GroupKFold

from reform.classifiers import PARAM_GRIDS, make_classifier
from reform.detector import training_pairs
from reform.features import DEFAULT_FEATURES
from reform.frame import Frame
from reform.splits import time_blocks

__all__ = ["N_FOLDS", "SCORING", "Tuning", "classifier_params", "tune"]

N_FOLDS = 5  # time blocks per sequence, one per cross-validation fold
SCORING = "accuracy"  # cross-validation objective: pairwise accuracy of the classifier


@dataclass(frozen=True)
class Tuning:
    """Cross-validated choice of one classifier's hyper-parameters on training frames.

    Attributes:
        classifier: the ready-made classifier's name.
        candidates: the grid's parameter settings, in the order tried.
        mean_score: (per candidate) mean cross-validated score.
        std_score: (per candidate) its standard deviation over folds.
        best_params: the chosen setting (highest mean score; ties: first).
        scoring: the objective, a scikit-learn scorer name.
        n_folds: folds (stretches of time).
        frames: training frames.
        pairs: training pairs.
    """

    classifier: str
    candidates: tuple[Mapping[str, Any], ...]
    mean_score: tuple[float, ...]
    std_score: tuple[float, ...]
    best_params: Mapping[str, Any]
    scoring: str
    n_folds: int
    frames: int
    pairs: int

    def to_json(self) -> dict[str, Any]:
        return {
            "classifier": self.classifier,
            "scoring": self.scoring,
            "n_folds": self.n_folds,
            "folds": "reform.time_blocks: each fold holds one stretch of time of every sequence",
            "frames": self.frames,
            "pairs": self.pairs,
            "best_params": dict(self.best_params),
            "grid": [
                {"params": dict(c), "mean": m, "std": s}
                for c, m, s in zip(self.candidates, self.mean_score, self.std_score, strict=True)
            ],
        }


def tune(
    name: str,
    frames: Sequence[Frame],
    *,
    features: Sequence[str] = DEFAULT_FEATURES,
    grid: Mapping[str, Sequence[Any]] | None = None,
    n_folds: int = N_FOLDS,
    scoring: str = SCORING,
    n_jobs: int | None = None,
) -> Tuning:
    """Chooses a ready-made classifier's hyper-parameters by time-blocked cross-validation.

    The pairs of ``frames`` are scored with ``GroupKFold`` over :func:`reform.time_blocks`
    (``n_folds`` stretches of time per sequence), so a fold never tests on the neighbours of
    frames it trained on.

    Args:
        name: a ready-made classifier (:data:`reform.classifiers.CLASSIFIERS`).
        frames: annotated training frames.
        features: pair features.
        grid: parameter grid in the classifier's own names; default
            :data:`reform.classifiers.PARAM_GRIDS` of ``name``.
        n_folds: folds, >= 2.
        scoring: a scikit-learn scorer name.
        n_jobs: parallel fits (scikit-learn's meaning).

    Returns:
        The :class:`Tuning`.
    """
    frames = tuple(frames)
    grid = PARAM_GRIDS[name] if grid is None else grid
    x, y, frame_of_pair = training_pairs(frames, features=features)
    blocks = time_blocks(frames, n_folds)[frame_of_pair]
    search = GridSearchCV(
        make_classifier(name),
        {key: list(values) for key, values in grid.items()},
        scoring=scoring,
        cv=GroupKFold(n_splits=n_folds),
        n_jobs=n_jobs,
        refit=False,
    )
    search.fit(x, y, groups=blocks)
    results = search.cv_results_
    return Tuning(
        classifier=name,
        candidates=tuple(_plain(params) for params in results["params"]),
        mean_score=tuple(float(v) for v in results["mean_test_score"]),
        std_score=tuple(float(v) for v in results["std_test_score"]),
        best_params=_plain(search.best_params_),
        scoring=scoring,
        n_folds=n_folds,
        frames=len(frames),
        pairs=int(y.size),
    )


def _plain(params: Mapping[str, Any]) -> dict[str, Any]:
    return {key: value.item() if hasattr(value, "item") else value for key, value in params.items()}


def classifier_params(name: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """Grid parameter names (``knn__n_neighbors``) -> keywords of the ready-made factory."""
    names = {
        "knn__n_neighbors": "n_neighbors",
        "estimator__min_samples_leaf": "min_samples_leaf",
        "n_estimators": "n_estimators",
        "logreg__C": "C",
    }
    out = {}
    for key, value in params.items():
        if key not in names:
            raise ValueError(f"{name}: cannot map grid parameter {key!r} to the factory")
        out[names[key]] = value
    return out

"""Time-blocked tuning of the classifiers' hyper-parameters (reform.tuning)."""

from __future__ import annotations

import json

import pytest
from toy_scenes import toy_frames

from reform.tuning import classifier_params, tune


def test_tune_uses_time_blocks_and_its_grid():
    frames = toy_frames(0, 40)
    tuning = tune("logistic-regression", frames, grid={"logreg__C": (0.01, 1.0)}, n_folds=4)
    assert [c["logreg__C"] for c in tuning.candidates] == [0.01, 1.0]
    assert tuning.best_params["logreg__C"] in (0.01, 1.0)
    assert all(0.5 < m <= 1.0 for m in tuning.mean_score)
    assert tuning.n_folds == 4 and tuning.frames == 40 and tuning.pairs == 40 * 55
    assert classifier_params("logistic-regression", tuning.best_params) == {
        "C": tuning.best_params["logreg__C"]
    }
    json.dumps(tuning.to_json())
    with pytest.raises(ValueError, match="cannot map grid parameter 'knn__p'"):
        classifier_params("weighted-knn", {"knn__p": 1})

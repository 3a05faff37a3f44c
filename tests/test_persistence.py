"""Model files: skops round trips, identical predictions; foreign, old and broken files refused."""

from __future__ import annotations

import functools
import zipfile
from fractions import Fraction

import numpy as np
import pytest
import sklearn
import skops.io as sio
from sklearn.exceptions import NotFittedError
from sklearn.linear_model import LogisticRegression
from toy_scenes import toy_frames

import reform
from reform import Reform
from reform.classifiers import CLASSIFIERS, make_classifier
from reform.persistence import FORMAT, FORMAT_VERSION, load_model, model_info, save_model


@functools.cache
def fitted(name: str) -> Reform:
    return Reform(make_classifier(name)).fit(toy_frames(0, 60))


@pytest.mark.parametrize("name", list(CLASSIFIERS))
def test_round_trip_gives_identical_predictions(name, tmp_path):
    model = fitted(name)
    path = save_model(model, tmp_path / "model.skops")
    assert zipfile.is_zipfile(path)  # a skops archive, not a pickle
    loaded = load_model(path)
    assert isinstance(loaded, Reform)
    assert loaded is not model
    frames = toy_frames(9, 30, sizes=(2, 3, 4), loners=3)
    assert loaded.predict(frames) == model.predict(frames)
    assert loaded.get_params(deep=False)["reconstruction"] == model.reconstruction
    assert loaded.training_summary_ == model.training_summary_


def test_file_says_what_it_holds(tmp_path):
    path = save_model(fitted("bagged-trees"), tmp_path / "model.skops")
    info = model_info(path)
    assert info["format"] == FORMAT
    assert info["versions"]["reform_sim"] == reform.__version__
    assert info["versions"]["scikit_learn"] == sklearn.__version__
    assert info["features"] == ["distance", "effort_angle"]
    assert info["classifier"] == "BaggingClassifier"
    assert info["training"]["frames"] == 60
    assert info["training"]["pairs"] == 60 * 55


def test_the_compiled_table_is_not_stored(tmp_path):
    model = fitted("bagged-trees")
    model.predict(toy_frames(3, 2))
    assert getattr(model, "_compiled", None) is not None
    path = save_model(model, tmp_path / "model.skops")
    assert path.stat().st_size < 2_000_000
    assert getattr(load_model(path), "_compiled", None) is None  # rebuilt on first predict


def payload(model: Reform, **changes) -> dict:
    data = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "versions": {"reform_sim": reform.__version__, "scikit_learn": sklearn.__version__},
        "model": model,
    }
    data.update(changes)
    return data


def test_foreign_types_are_refused(tmp_path):
    path = tmp_path / "evil.skops"
    sio.dump(payload(fitted("logistic-regression"), extra=Fraction(1, 3)), path)
    with pytest.raises(ValueError, match=r"refusing to load: .*\['fractions.Fraction'\]"):
        load_model(path)
    assert isinstance(load_model(path, trusted=["fractions.Fraction"]), Reform)


def test_other_versions_are_refused(tmp_path):
    model = fitted("logistic-regression")
    old = tmp_path / "old.skops"
    sio.dump(payload(model, versions={"reform_sim": "0.0.1", "scikit_learn": "1.9.1"}), old)
    with pytest.raises(ValueError, match=r"written by reform-sim 0.0.1, this is reform-sim"):
        load_model(old)
    other_sklearn = tmp_path / "sklearn.skops"
    versions = {"reform_sim": reform.__version__, "scikit_learn": "1.5.2"}
    sio.dump(payload(model, versions=versions), other_sklearn)
    with pytest.raises(ValueError, match="written with scikit-learn 1.5.2"):
        load_model(other_sklearn)
    newer_format = tmp_path / "format.skops"
    sio.dump(payload(model, format_version=99), newer_format)
    with pytest.raises(ValueError, match="format version 99"):
        load_model(newer_format)


def test_files_that_are_not_reform_models_are_refused(tmp_path):
    plain = tmp_path / "plain.skops"
    sio.dump(LogisticRegression(), plain)
    with pytest.raises(ValueError, match="not a REFORM model file"):
        load_model(plain)
    text = tmp_path / "model.skops"
    text.write_text("hello")
    with pytest.raises(ValueError, match="not a skops model file"):
        load_model(text)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_model(tmp_path / "missing.skops")
    wrong = tmp_path / "wrong.skops"
    sio.dump(payload(LogisticRegression()), wrong)
    with pytest.raises(ValueError, match="model is a LogisticRegression, not a reform.Reform"):
        load_model(wrong)


def test_only_fitted_reform_models_are_saved(tmp_path):
    with pytest.raises(NotFittedError):
        save_model(Reform(), tmp_path / "m.skops")
    with pytest.raises(TypeError, match="model must be a reform.Reform, got LogisticRegression"):
        save_model(LogisticRegression(), tmp_path / "m.skops")
    assert not (tmp_path / "m.skops").exists()


def fresh(name: str = "logistic-regression") -> Reform:
    """A fitted model of our own, free to be altered (``fitted`` is shared between tests)."""
    return Reform(make_classifier(name)).fit(toy_frames(0, 60))


def _features_disagree() -> dict:
    model = fresh("bagged-trees")  # fitted on distance and effort_angle
    model.features_ = ("distance",)
    return payload(model)


def _unknown_features() -> dict:
    model = fresh()
    model.features_ = ("distance", "loudness")
    return payload(model)


def _other_classes() -> dict:
    model = fresh()
    x = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]])
    model.classifier_ = LogisticRegression().fit(x, np.array([0, 1, 2, 2]))
    return payload(model)


def _unfitted_classifier() -> dict:
    model = fresh()
    model.classifier_ = LogisticRegression()
    return payload(model)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        pytest.param(
            _features_disagree,
            r"inconsistent model: features_ \['distance'\] gives 1 feature\(s\) per pair, "
            r"expected the classifier to take as many, found a BaggingClassifier fitted on 2 "
            r"\(n_features_in_\)",
            id="features-disagree-with-classifier",
        ),
        pytest.param(
            _unknown_features,
            r"the model's features_ are not valid: features must be among .*, got 'loudness'",
            id="unknown-features",
        ),
        pytest.param(
            lambda: payload(fresh(), features=["distance", "head_distance"]),
            r"the file lists features \['distance', 'head_distance'\], expected the model's own "
            r"features_ \['distance', 'effort_angle'\]",
            id="file-lists-other-features",
        ),
        pytest.param(
            _other_classes,
            r"inconsistent model: expected a pair classifier of classes \[0, 1\] \(apart, "
            r"together\), found a LogisticRegression with classes_ \[0, 1, 2\]",
            id="other-classes",
        ),
        pytest.param(
            lambda: payload(Reform()),
            r"expected a fitted reform\.Reform, found an unfitted one \(no classifier_ or "
            r"features_\)",
            id="unfitted-model",
        ),
        pytest.param(
            _unfitted_classifier,
            r"expected a fitted pair classifier in the model, found an unfitted "
            r"LogisticRegression",
            id="unfitted-classifier",
        ),
    ],
)
def test_a_broken_model_file_is_refused_naming_it(make, message, tmp_path):
    path = tmp_path / "broken.skops"
    sio.dump(make(), path)
    with pytest.raises(ValueError, match=r"broken\.skops: " + message):
        load_model(path)
    with pytest.raises(ValueError, match=message):
        model_info(path)


def test_a_folder_is_not_a_model_file(tmp_path):
    folder = tmp_path / "model.skops"
    folder.mkdir()
    with pytest.raises(ValueError, match=r"model file .*model\.skops is a folder: expected a "):
        load_model(folder)
    with pytest.raises(ValueError, match="is a folder"):
        model_info(folder)


def test_the_command_line_says_the_model_is_a_folder(tmp_path, capsys):
    from reform.datasets import write_parquet
    from sim.cli import main

    data = tmp_path / "toy.parquet"
    write_parquet(reform.Dataset(frames=tuple(toy_frames(1, 4)), name="toy"), data)
    folder = tmp_path / "model.skops"
    folder.mkdir()
    assert main(["evaluate", "--model", str(folder), "--data", str(data)]) == 2
    assert "model.skops is a folder: expected a skops file" in capsys.readouterr().err

"""Saving and loading fitted REFORM models with skops: no pickle, no code run from a file.

A model file is a skops archive of one dictionary: the fitted :class:`reform.Reform` and, beside
it, what a reader wants to know without trusting the model first: the file format, the versions
of reform-sim and scikit-learn that wrote it, the features, the classifier and a summary of the
training data. ``load_model`` lists the types the file would build and refuses any outside a
fixed allow-list (scikit-learn's own estimators are trusted by skops already), so a file from
someone else cannot run code; it also refuses a file written by another reform-sim version,
and a model that is unfitted or whose parts disagree (its classifier fitted on another number of
features than it names), so that a bad file fails when it is loaded, naming the file, rather than
on first use.

skops is imported only inside these functions.
"""

from __future__ import annotations

import io
import os
import zipfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from reform.atomic import atomic_open
from reform.detector import Reform
from reform.features import check_features

FORMAT = "reform-sim model"
FORMAT_VERSION = 1

# Types a REFORM model file may hold beyond what skops trusts by default: the detector itself and
# the compiled internals of scikit-learn's trees and neighbour searches.
TRUSTED_TYPES = (
    "reform.detector.Reform",
    "sklearn.tree._tree.Tree",
    "sklearn.neighbors._kd_tree.KDTree",
    "sklearn.neighbors._ball_tree.BallTree",
    "sklearn.metrics._dist_metrics.EuclideanDistance64",
    "sklearn.metrics._dist_metrics.ManhattanDistance64",
    "sklearn.metrics._dist_metrics.ChebyshevDistance64",
    "sklearn.metrics._dist_metrics.MinkowskiDistance64",
)

__all__ = ["FORMAT", "FORMAT_VERSION", "TRUSTED_TYPES", "load_model", "model_info", "save_model"]


def _skops_io() -> Any:
    try:
        import skops.io as sio
    except ImportError as exc:  # pragma: no cover - skops is a dependency of the project
        raise ImportError(
            "saving REFORM models needs skops: pip install 'skops>=0.16,<0.17'"
        ) from exc
    return sio


def _versions() -> dict[str, str]:
    import sklearn

    import reform

    return {"reform_sim": reform.__version__, "scikit_learn": sklearn.__version__}


def save_model(model: Reform, path: str | os.PathLike[str]) -> Path:
    """Writes a fitted REFORM model to a skops file (atomically).

    Args:
        model: a fitted :class:`reform.Reform`.
        path: the file to write, conventionally ``*.skops``.

    Returns:
        The path written.

    Raises:
        TypeError: if ``model`` is not a Reform.
        sklearn.exceptions.NotFittedError: if it is not fitted.
    """
    from sklearn.utils.validation import check_is_fitted

    if not isinstance(model, Reform):
        raise TypeError(f"model must be a reform.Reform, got {type(model).__name__}")
    check_is_fitted(model, "classifier_")
    sio = _skops_io()
    payload = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "versions": _versions(),
        "features": list(model.features_),
        "classifier": type(model.classifier_).__name__,
        "classifier_repr": repr(model.classifier_),
        "reconstruction": model.reconstruction,
        "threshold": model.threshold,
        "training": model.training_summary_,
        "model": model,
    }
    data = sio.dumps(payload)
    path = Path(path)
    with atomic_open(path, "wb") as handle:
        handle.write(data)
    return path


def _read(path: Path) -> bytes:
    if path.is_dir():
        raise ValueError(f"model file {path} is a folder: expected a skops file (*.skops)")
    if not path.exists():
        raise FileNotFoundError(f"model file {path} does not exist")
    if not path.is_file():
        raise ValueError(f"model file {path} is not a regular file: expected a skops file")
    data = path.read_bytes()
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            if "schema.json" not in archive.namelist():
                raise ValueError(f"{path}: not a skops model file (no schema.json inside)")
    except zipfile.BadZipFile as exc:
        raise ValueError(f"{path}: not a skops model file (not a zip archive)") from exc
    return data


def _check_types(path: Path, data: bytes, trusted: Iterable[str]) -> list[str]:
    sio = _skops_io()
    untrusted = sio.get_untrusted_types(data=data)
    allowed = set(TRUSTED_TYPES) | set(trusted)
    foreign = sorted(set(untrusted) - allowed)
    if foreign:
        raise ValueError(
            f"{path}: refusing to load: the file holds types outside the trusted list: {foreign} "
            "(a REFORM model holds only scikit-learn and reform types). If you know where the "
            "file comes from and trust it, pass trusted=[...] naming these types."
        )
    return list(untrusted)


def load_model(path: str | os.PathLike[str], *, trusted: Iterable[str] = ()) -> Reform:
    """Reads a REFORM model written by :func:`save_model`.

    Args:
        path: the skops file.
        trusted: extra type names to trust (for a classifier of your own); by default only
            :data:`TRUSTED_TYPES` and skops' defaults.

    Returns:
        The fitted :class:`reform.Reform`.

    Raises:
        FileNotFoundError: if the file does not exist.
        ValueError: if the path is a folder, the file is not a skops file, holds types outside
            the trusted list, is not a REFORM model file, was written by another version of
            reform-sim or a scikit-learn of another minor version, or holds a Reform that is
            not fitted or whose parts disagree (features unknown, a classifier fitted on
            another number of features than ``features_`` names, classes other than [0, 1]).
    """
    path = Path(path)
    data = _read(path)
    untrusted = _check_types(path, data, trusted)
    sio = _skops_io()
    payload = sio.loads(data, trusted=untrusted)
    return _unwrap(path, payload)


def model_info(path: str | os.PathLike[str], *, trusted: Iterable[str] = ()) -> dict[str, Any]:
    """The metadata of a model file (versions, features, classifier, training summary)."""
    path = Path(path)
    data = _read(path)
    untrusted = _check_types(path, data, trusted)
    payload = _skops_io().loads(data, trusted=untrusted)
    _unwrap(path, payload)
    return {key: value for key, value in payload.items() if key != "model"}


def _unwrap(path: Path, payload: Any) -> Reform:
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ValueError(f"{path}: not a REFORM model file (expected format {FORMAT!r})")
    if payload.get("format_version") != FORMAT_VERSION:
        raise ValueError(
            f"{path}: model file format version {payload.get('format_version')!r}, "
            f"this reform-sim reads version {FORMAT_VERSION}"
        )
    versions = payload.get("versions") or {}
    current = _versions()
    written = versions.get("reform_sim")
    if written != current["reform_sim"]:
        raise ValueError(
            f"{path}: model written by reform-sim {written}, this is reform-sim "
            f"{current['reform_sim']}; retrain it with `reform-sim train` (or install {written})"
        )
    written_sklearn = str(versions.get("scikit_learn", ""))
    if written_sklearn.split(".")[:2] != current["scikit_learn"].split(".")[:2]:
        raise ValueError(
            f"{path}: model written with scikit-learn {written_sklearn}, this is scikit-learn "
            f"{current['scikit_learn']}; retrain it with `reform-sim train`"
        )
    model = payload.get("model")
    if not isinstance(model, Reform):
        raise ValueError(
            f"{path}: the file's model is a {type(model).__name__}, not a reform.Reform"
        )
    _check_model(path, model, payload.get("features"))
    return model


def _check_model(path: Path, model: Reform, listed: Any) -> None:
    """Refuses a Reform that is not fitted or whose parts disagree, naming the file: such a
    model would load and then fail on first use, far from its file."""
    from sklearn.exceptions import NotFittedError
    from sklearn.utils.validation import check_is_fitted

    missing = [name for name in ("classifier_", "features_") if not hasattr(model, name)]
    if missing:
        raise ValueError(
            f"{path}: expected a fitted reform.Reform, found an unfitted one (no "
            f"{' or '.join(missing)}); save a model after fit, e.g. with `reform-sim train`"
        )
    try:
        features = check_features(model.features_)
    except ValueError as exc:
        raise ValueError(f"{path}: the model's features_ are not valid: {exc}") from exc
    if listed is not None and list(listed) != list(features):
        raise ValueError(
            f"{path}: the file lists features {list(listed)}, expected the model's own "
            f"features_ {list(features)}"
        )
    classifier = model.classifier_
    name = type(classifier).__name__
    try:
        check_is_fitted(classifier)
    except (NotFittedError, TypeError) as exc:
        raise ValueError(
            f"{path}: expected a fitted pair classifier in the model, found an unfitted {name}"
        ) from exc
    n_in = getattr(classifier, "n_features_in_", None)
    if n_in is not None and int(n_in) != len(features):
        raise ValueError(
            f"{path}: inconsistent model: features_ {list(features)} gives {len(features)} "
            f"feature(s) per pair, expected the classifier to take as many, found a {name} "
            f"fitted on {int(n_in)} (n_features_in_)"
        )
    classes = getattr(classifier, "classes_", None)
    found = None if classes is None else np.asarray(classes).tolist()
    if found != [0, 1]:
        raise ValueError(
            f"{path}: inconsistent model: expected a pair classifier of classes [0, 1] "
            f"(apart, together), found a {name} with classes_ {found}"
        )

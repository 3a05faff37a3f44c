"""REFORM's named configurations in the catalogue (``reform-trained``, ``reform-relative``,
``reform-correlation``): fitted on the training frames `reform.prepare_detector` is given, each
the same detector as `reform.Reform` built with its options by hand."""

from __future__ import annotations

import pytest
from test_detector import held_out_frames, training_frames
from test_detector_options import scaled

from reform import Reform, make_detector, prepare_detector
from reform.catalogue import (
    _REFORM_CALIBRATIONS,
    _REFORM_CLASSIFIERS,
    _REFORM_FEATURE_SETS,
    _REFORM_RECONSTRUCTIONS,
)
from reform.classifiers import CLASSIFIERS, make_classifier
from reform.detector import CALIBRATIONS
from reform.detectors import DetectorError, detector_info
from reform.features import FEATURE_SETS
from reform.reconstruction import RECONSTRUCTIONS

CONFIGURATIONS = {
    "reform-trained": {"features": "paper", "reconstruction": "union"},
    "reform-relative": {"features": "relative", "reconstruction": "union"},
    "reform-correlation": {"features": "paper", "reconstruction": "correlation"},
}


def test_the_catalogues_choices_are_the_modules_own():
    # The catalogue keeps literals so that listing it imports nothing heavy.
    assert set(_REFORM_CLASSIFIERS) == set(CLASSIFIERS)
    assert set(_REFORM_FEATURE_SETS) == set(FEATURE_SETS)
    assert set(_REFORM_RECONSTRUCTIONS) == set(RECONSTRUCTIONS)
    assert set(_REFORM_CALIBRATIONS) == {"none", *CALIBRATIONS}


@pytest.mark.parametrize("name", sorted(CONFIGURATIONS))
def test_each_configuration_learns_from_the_training_frames_it_is_given(name):
    info = detector_info(name)
    assert info.needs == "training"
    detector = prepare_detector(name, make_detector(name), training=training_frames())
    by_hand = Reform(make_classifier("bagged-trees"), **CONFIGURATIONS[name]).fit(training_frames())
    assert detector.predict(held_out_frames()) == by_hand.predict(held_out_frames())


@pytest.mark.parametrize("name", sorted(CONFIGURATIONS))
def test_without_training_frames_it_says_so_in_one_line(name):
    with pytest.raises(DetectorError, match=f"^{name}: learns its settings from annotated"):
        prepare_detector(name, make_detector(name), training=None)


def test_options_reach_the_detector():
    detector = make_detector(
        "reform-correlation", classifier="logistic-regression", calibration="isotonic"
    )
    assert (detector.reconstruction, detector.calibration) == ("correlation", "isotonic")
    assert type(detector.classifier) is type(make_classifier("logistic-regression"))


def test_the_relative_configuration_answers_alike_at_another_scale():
    detector = prepare_detector(
        "reform-relative", make_detector("reform-relative"), training=training_frames()
    )
    frames = held_out_frames()
    assert detector.predict([scaled(f, 2.5) for f in frames]) == detector.predict(frames)


def test_an_unknown_choice_is_refused_naming_the_accepted_ones():
    with pytest.raises(DetectorError, match="classifier.*weighted-knn"):
        make_detector("reform-trained", classifier="svm")

"""One contract test over every registered detector (reform.detector_checks), as scikit-learn's
``parametrize_with_checks`` runs over every estimator; and detectors that break each check, so
that every check is seen to fail."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
from toy_scenes import toy_frames

from reform import (
    Dataset,
    DetectorError,
    Majority,
    Reform,
    detector_names,
    make_detector,
    save_model,
)
from reform.classifiers import make_classifier
from reform.detector_checks import (
    DETECTOR_CHECKS,
    DetectorCheckError,
    check_detector,
    check_no_frames_nobody_and_one_person,
    check_partition_per_frame,
    check_relabelling,
    check_rigid_motion,
    check_scenes,
    check_the_same_answer_twice,
)
from reform.detectors import prepare_detector


@pytest.fixture(scope="module")
def model_path(tmp_path_factory) -> Path:
    model = Reform(make_classifier("logistic-regression")).fit(toy_frames(0, 30))
    return save_model(model, tmp_path_factory.mktemp("model") / "model.skops")


def options_for(name: str, model_path: Path) -> dict:
    """What each built-in needs to be made; a new built-in that needs options fails here."""
    if name == "dante":
        return {"model": _tiny_dante(model_path.parent)}
    return {"reform": {"model": model_path}}.get(name, {})


@functools.cache
def _tiny_dante(folder: Path) -> Path:
    """A DANTE trained for a few epochs on toy frames, once per module (the extra
    reform-sim[dante], which CI installs)."""
    pytest.importorskip("torch")
    from reform.dante import Dante

    model = Dante(epochs=3, batch_size=256, learning_rate=1e-3, random_state=0)
    return model.fit(toy_frames(0, 30)).save(folder / "dante.safetensors")


def ready(name: str, model_path: Path):
    """The catalogue's detector ``name`` made and given what it needs (reform.prepare_detector):
    a dataset shipping GCFF settings for every sequence of the check scenes, training frames
    that are not the check scenes."""
    scenes = tuple({f.sequence: f for f in check_scenes()}.values())  # a frame of each sequence
    settings = {"stride_m": 0.7, "mdl_m2": 3.0}
    dataset = Dataset(
        frames=scenes,
        name="check-scenes",
        metadata={"settings_gc_by_sequence": {f.sequence: settings for f in scenes}},
    )
    made = make_detector(name, **options_for(name, model_path))
    return prepare_detector(name, made, dataset=dataset, training=toy_frames(0, 30))


@pytest.mark.parametrize("check", DETECTOR_CHECKS, ids=lambda check: check.__name__)
@pytest.mark.parametrize("name", detector_names())
def test_every_registered_detector_keeps_the_contract(name, check, model_path):
    check(name, ready(name, model_path))


def test_a_detector_that_needs_a_dataset_or_training_frames_says_so():
    with pytest.raises(DetectorError, match=r"^gcff-own: runs on a dataset's own settings"):
        prepare_detector("gcff-own", make_detector("gcff-own"))
    with pytest.raises(DetectorError, match=r"^gcff-tuned: learns its settings from annotated"):
        prepare_detector("gcff-tuned", make_detector("gcff-tuned"), training=[])
    bare = Dataset(frames=tuple(check_scenes()[:1]), name="bare")
    with pytest.raises(DetectorError, match=r"^gcff-own: dataset 'bare': sequence 'circles' "):
        prepare_detector("gcff-own", make_detector("gcff-own"), dataset=bare)


def test_reform_finds_the_groups_of_the_check_scenes(model_path):
    """The checks' scenes are clear: the contract is not met by finding no group at all."""
    frames = check_scenes()
    predicted = make_detector("reform", model=model_path).predict(frames)
    for frame, partition in zip(frames, predicted, strict=True):
        found = {frozenset(g) for g in partition if len(g) > 1}
        assert found == {frozenset(g) for g in frame.groups}


# ------------------------------------------------------------------------------------------------
# Detectors that break one check each


def _in_pairs(ids: list[int]) -> list[tuple[int, ...]]:
    """``ids`` grouped two by two in their order (the last alone when they are odd)."""
    return [tuple(ids[k : k + 2]) for k in range(0, len(ids), 2)]


class _Pairs(Majority):
    """Pairs people in the order they are listed: depends on the order and the ids."""

    def predict(self, frames):
        return [_in_pairs([int(i) for i in frame.ids]) for frame in frames]


class _Sorted(Majority):
    """Pairs people by id: the same for any listing order, not for other ids."""

    def predict(self, frames):
        return [_in_pairs(sorted(int(i) for i in frame.ids)) for frame in frames]


class _LeftAndRight(Majority):
    """Groups people by which side of x = 5 m they stand on: depends on where the scene is."""

    def predict(self, frames):
        out = []
        for frame in frames:
            left = frame.position[:, 0] < 5
            groups = (frame.ids[left].tolist(), frame.ids[~left].tolist())
            out.append([tuple(g) for g in groups if g])
        return out


class _Coin(Majority):
    """Pairs two people at random: a different answer each time."""

    def __init__(self):
        self.rng = np.random.default_rng(0)

    def predict(self, frames):
        out = []
        for frame in frames:
            ids = [int(i) for i in self.rng.permutation(frame.ids)]
            pair = [tuple(ids[:2])] if len(ids) > 1 else []
            out.append(pair + [(i,) for i in ids[2:]] if pair else [(i,) for i in ids])
        return out


class _Forgets(Majority):
    def predict(self, frames):
        return [[(int(f.ids[0]),)] if f.n_people else [] for f in frames]


class _NoBodyFails(Majority):
    def predict(self, frames):
        return [[(0,)] if f.n_people == 0 else [(int(i),) for i in f.ids] for f in frames]


class _AnswersNothing(Majority):
    """Answers an empty batch with one empty partition."""

    def predict(self, frames):
        return [[(int(i),) for i in f.ids] for f in frames] or [[]]


class _LosesTheOnlyPerson(Majority):
    """Leaves a person alone in a frame out of the partition."""

    def predict(self, frames):
        return [[] if f.n_people == 1 else [(int(i),) for i in f.ids] for f in frames]


@pytest.mark.parametrize(
    ("detector", "check", "message"),
    [
        (
            _Forgets(),
            check_partition_per_frame,
            r"broken: detector output for frame 0 .* person 2 is in no group",
        ),
        (_NoBodyFails(), check_no_frames_nobody_and_one_person, r"broken: detector output"),
        (
            _AnswersNothing(),
            check_no_frames_nobody_and_one_person,
            r"broken: detector returned 1 partitions for 0 frames",
        ),
        (
            _LosesTheOnlyPerson(),
            check_no_frames_nobody_and_one_person,
            r"broken: detector output for frame 1 .* person 7 is in no group",
        ),
        (_Coin(), check_the_same_answer_twice, r"broken: fails the same answer twice: frame 0"),
        (_Pairs(), check_relabelling, r"broken: fails relabelling: frame 0: \[.*\] became"),
        (_Sorted(), check_relabelling, r"broken: fails relabelling: frame 0"),
        (_LeftAndRight(), check_rigid_motion, r"broken: fails rigid motion: frame 0 turned"),
    ],
    ids=[
        "forgets",
        "nobody",
        "empty-batch",
        "one-person",
        "coin",
        "listing-order",
        "ids",
        "where-it-stands",
    ],
)
def test_a_detector_that_breaks_a_check_fails_it(detector, check, message):
    with pytest.raises(DetectorError, match=message):
        check("broken", detector)


def test_check_detector_runs_every_check_by_name_or_object(model_path):
    check_detector("gcff")
    check_detector(make_detector("reform", model=model_path), name="reform")
    with pytest.raises(DetectorCheckError, match=r"^_LeftAndRight: fails rigid motion"):
        check_detector(_LeftAndRight())
    with pytest.raises(ValueError, match="options are for a detector given by name"):
        check_detector(Majority(), stride=0.5)
    with pytest.raises(DetectorError, match="unknown detector|no detector"):
        check_detector("no-such-detector")

"""Temporal filters (reform.smoothing): the sliding majority and hysteresis, hand-computed on
short sequences; causal, per sequence, in any input order; refused in one line where they
cannot work; in the catalogue as ``smoothed`` and ``hysteresis``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from toy_scenes import toy_frames

from reform import Frame, make_detector, prepare_detector
from reform.detector_checks import check_detector
from reform.detectors import DetectorError
from reform.gcff import Gcff
from reform.smoothing import Hysteresis, SlidingMajority

APART = ((1,), (2,), (3,))
PAIR = ((1, 2), (3,))


def line(t: float, sequence: str = "s") -> Frame:
    return Frame(
        ids=[1, 2, 3],
        position=np.c_[np.arange(3.0), np.zeros(3)],
        yaw=np.zeros(3),
        time=t,
        sequence=sequence,
    )


class Script:
    """A detector that answers from a script, by frame time (fits nothing)."""

    def __init__(self, answers: dict[float, tuple], proba: dict[float, float] | None = None):
        self.answers = answers
        self.proba = proba

    def predict(self, frames):
        return [self.answers[round(f.time, 6)] for f in frames]

    def predict_pair_proba(self, frames):
        # pairs (1,2), (1,3), (2,3) in row order; only (1,2) varies
        return [np.array([self.proba[round(f.time, 6)], 0.0, 0.0]) for f in frames]


FLICKER = {round(0.1 * k, 6): (APART if k % 3 == 0 else PAIR) for k in range(10)}


def test_the_majority_over_half_a_second_by_hand():
    frames = [line(0.1 * k) for k in range(10)]
    got = SlidingMajority(Script(FLICKER), window=0.5).predict(frames)
    # Frame k votes over frames k-4..k (times in (t - 0.5, t]); pair (1,2) is together in every
    # frame but 0, 3, 6, 9. Votes: k=0 0/1, 1 1/2, 2 2/3, 3 2/4, 4 3/5, 5 4/5, 6 3/5, 7 4/5 ...
    assert got == [APART, APART, PAIR, APART, PAIR, PAIR, PAIR, PAIR, PAIR, PAIR]


def test_a_window_shorter_than_the_frame_interval_changes_nothing():
    frames = [line(0.1 * k) for k in range(10)]
    assert SlidingMajority(Script(FLICKER), window=0.05).predict(frames) == [
        FLICKER[round(0.1 * k, 6)] for k in range(10)
    ]


def test_causal_per_sequence_and_in_any_order():
    frames = [line(0.1 * k, sequence) for sequence in ("a", "b") for k in range(10)]
    script = Script(FLICKER)
    whole = SlidingMajority(script, window=0.5).predict(frames)
    assert whole[:10] == whole[10:]  # each sequence on its own
    prefix = SlidingMajority(script, window=0.5).predict(frames[:6])
    assert prefix == whole[:6]  # a frame's answer depends only on the frames before it
    order = np.random.default_rng(0).permutation(len(frames))
    shuffled = SlidingMajority(script, window=0.5).predict([frames[k] for k in order])
    assert shuffled == [whole[k] for k in order]


def test_hysteresis_by_hand():
    # pair (1,2)'s probability over time; high 0.7, low 0.3
    proba = {0.0: 0.6, 1.0: 0.4, 2.0: 0.25, 3.0: 0.6, 4.0: 0.75, 5.0: 0.5}
    frames = [line(t) for t in sorted(proba)]
    got = Hysteresis(Script({}, proba), high=0.7, low=0.3, window=2.0).predict(frames)
    # 0.6 fresh: its own decision, together; 0.4 stays together (above low); 0.25 parts;
    # 0.6 stays apart (below high); 0.75 joins; 0.5 stays together.
    assert got == [PAIR, PAIR, APART, APART, PAIR, PAIR]


def test_hysteresis_starts_afresh_after_a_gap_longer_than_the_window():
    proba = {0.0: 0.8, 5.0: 0.4}
    frames = [line(t) for t in sorted(proba)]
    assert Hysteresis(Script({}, proba), window=2.0).predict(frames) == [PAIR, APART]
    assert Hysteresis(Script({}, proba), window=10.0).predict(frames) == [PAIR, PAIR]


def test_the_filters_keep_the_detector_contract():
    check_detector(SlidingMajority(Gcff(), window=2.0), name="smoothed")
    trained = prepare_detector(
        "hysteresis", make_detector("hysteresis"), training=toy_frames(0, 40)
    )
    check_detector(trained, name="hysteresis")


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: SlidingMajority(Gcff(), window=0), "window must lie in (0, 3600] seconds, got 0"),
        (lambda: Hysteresis(Gcff()), "needs a detector with pair probabilities"),
        (
            lambda: Hysteresis(Script({}, {}), high=0.4),
            "high must lie in (0.5, 1), got 0.4",
        ),
    ],
)
def test_filters_that_cannot_work_are_refused_in_one_line(make, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        make().predict([line(0.0)])


def test_the_catalogue_wraps_a_name_or_a_settings_file(tmp_path):
    assert make_detector("smoothed", detector="hvff").detector.__class__.__name__ == "Hvff"
    settings = tmp_path / "gcff.json"
    settings.write_text(
        json.dumps(
            {
                "format": "reform-sim detector settings",
                "version": 1,
                "detector": "gcff",
                "options": {"stride": 0.6, "mdl": 2.0},
            }
        )
    )
    inner = make_detector("smoothed", detector=str(settings)).detector
    assert (inner.stride, inner.mdl) == (0.6, 2.0)
    with pytest.raises(DetectorError, match="detector='reform-trained' learns first"):
        make_detector("smoothed", detector="reform-trained")
    with pytest.raises(DetectorError, match="hysteresis: learns its settings"):
        prepare_detector("hysteresis", make_detector("hysteresis"), training=None)

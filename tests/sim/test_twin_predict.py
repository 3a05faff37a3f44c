"""A twin's predictions calibrated at the place: the detectors' consensus, each detector's
agreement with it, and the line from agreement to F1 fitted on the twin."""

from __future__ import annotations

import numpy as np
import pytest

from reform.frame import Frame
from sim.twins.predict import (
    MIN_CONSENSUS,
    agreements,
    calibrated,
    catalogue_candidates,
    consensus,
    method_weights,
)


def _frame(people: int = 4) -> Frame:
    return Frame(
        ids=np.arange(1, people + 1),
        position=np.arange(2 * people, dtype=float).reshape(people, 2),
        yaw=np.zeros(people),
    )


def test_the_consensus_keeps_the_pairs_more_than_half_put_together():
    frame = _frame(3)
    votes = [[((1, 2), (3,))], [((1, 2, 3),)], [((1,), (2,), (3,))]]
    assert consensus([frame], votes) == [((1, 2), (3,))]  # 1-2: two of three; 1-3, 2-3: one
    even = [[((1, 2), (3,))], [((1, 2), (3,))], [((1,), (2,), (3,))], [((1,), (2,), (3,))]]
    assert consensus([frame], even) == [((1,), (2,), (3,))]  # half is not more than half


def test_pairs_linked_in_a_chain_make_one_group():
    frame = _frame(4)
    votes = [[((1, 2), (3, 4))], [((1, 2, 3), (4,))], [((1,), (2, 3), (4,))]]
    # 1-2 and 2-3 carry (two of three each), 1-3 does not: the chain 1-2-3 is one group
    assert consensus([frame], votes) == [((1, 2, 3), (4,))]


def test_the_variants_of_one_method_share_its_one_vote():
    frame = _frame(3)
    variants = [[((1, 2), (3,))]] * 3  # three variants of one method put 1 and 2 together
    others = [[((1,), (2,), (3,))]] * 2  # two other methods do not
    assert consensus([frame], variants + others) == [((1, 2), (3,))]  # three votes of five
    shares = method_weights({"v1": "V", "v2": "V", "v3": "V", "x": "", "y": ""})
    assert shares == pytest.approx({"v1": 1 / 3, "v2": 1 / 3, "v3": 1 / 3, "x": 1.0, "y": 1.0})
    weights = [shares[k] for k in ("v1", "v2", "v3", "x", "y")]
    assert consensus([frame], variants + others, weights) == [((1,), (2,), (3,))]  # one of three
    outputs = dict(zip(["v1", "v2", "v3", "x", "y"], variants + others, strict=True))
    method = {"v1": "V", "v2": "V", "v3": "V", "x": "", "y": ""}
    assert agreements([frame], outputs)["v1"] == 1.0
    assert agreements([frame], outputs, voters=method)["v1"] == 0.0


def test_a_catalogued_detector_votes_with_the_method_it_implements():
    method = {c.label: c.method for c in catalogue_candidates() if c.votes}
    assert method["gcff-tuned"] == method["gcff"] != ""  # GCFF's paper
    assert method["smoothed"] == method["gcff"]  # it filters GCFF, by default
    assert len({method[k] for k in ("reform-trained", "reform-relative", "hysteresis")}) == 1
    assert method["proximity"] == "" and method["hvff"] != method["gcff"]


def test_agreement_is_each_detectors_f1_against_the_consensus_and_majority_has_no_vote():
    frames = [_frame(4)] * 2
    together = [((1, 2), (3, 4))] * 2
    outputs = {
        "a": together,
        "b": together,
        "c": together,
        "majority": [((1,), (2,), (3,), (4,))] * 2,
    }
    agreed = agreements(frames, outputs)
    assert agreed == {"a": 1.0, "b": 1.0, "c": 1.0, "majority": 0.0}
    # the majority baseline does not vote: two detectors are too few for a consensus
    assert MIN_CONSENSUS == 3
    too_few = {"a": together, "b": together, "majority": outputs["majority"]}
    assert agreements(frames, too_few) is None


def test_the_line_from_agreement_to_f1_on_the_twin_is_applied_at_the_place():
    on_twin = {"a": 0.9, "b": 0.7, "c": 0.5}
    twin_f1 = {k: 0.1 + 0.8 * v for k, v in on_twin.items()}
    at_place = {"a": 0.8, "b": 0.4, "c": 0.0}
    out = calibrated(twin_f1, on_twin, at_place)
    assert out == pytest.approx({"a": 0.74, "b": 0.42, "c": 0.1})
    # clipped to [0, 1]; agreements that do not differ on the twin draw no line
    assert calibrated({"a": 1.0, "b": 0.0}, {"a": 1.0, "b": 0.0}, {"a": 2.0, "b": -1.0}) == {
        "a": 1.0,
        "b": 0.0,
    }
    assert calibrated(twin_f1, dict.fromkeys(on_twin, 0.6), at_place) is None


def test_the_line_is_fitted_on_the_detectors_named_and_applied_to_every_one():
    on_twin = {"a": 0.9, "b": 0.5, "variant": 0.7}
    twin_f1 = {"a": 0.9, "b": 0.5, "variant": 0.1}  # the variant is off the catalogue's line
    at_place = {"a": 0.6, "b": 0.4, "variant": 0.8}
    out = calibrated(twin_f1, on_twin, at_place, fitted_on=["a", "b"])
    assert out == pytest.approx({"a": 0.6, "b": 0.4, "variant": 0.8})

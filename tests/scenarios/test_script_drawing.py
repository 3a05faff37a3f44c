"""Drawing a script: the shortcuts taken while it is drawn give what the plain calls give."""

from __future__ import annotations

import gc
import math

import numpy as np
import pytest

import scenarios
from scenarios import Intent, TimelineBuilder
from scenarios.conversation import converse
from scenarios.formation import separate

PLACES = np.array([[0.0, 0.6], [0.6, 0.0], [0.0, -0.6], [-0.6, 0.05]])  # metres
FACINGS = np.array([-1.5, 3.1, 1.5, 0.0])  # radians


def _talk(head_noise: float, seed: int = 7) -> tuple[list, TimelineBuilder, np.random.Generator]:
    builder = TimelineBuilder([1, 2, 3, 4])
    rng = np.random.default_rng(seed)
    turns = converse(
        builder, [1, 2, 3, 4], PLACES, FACINGS, start=0.0, end=120.0, rng=rng, head_noise=head_noise
    )
    return turns, builder, rng


def test_set_many_is_set_for_each_agent_in_turn() -> None:
    intents = [Intent(goal=(float(k), 0.0)) for k in range(4)]
    one_by_one, at_once = TimelineBuilder([1, 2, 3]), TimelineBuilder([1, 2, 3])
    for builder, many in ((one_by_one, False), (at_once, True)):
        builder.set(2.0, 3, intents[3])
        if many:
            builder.set_many(1.0, (1, 2, 1), intents[:3])  # the later of two for 1 wins
        else:
            for agent, intent in zip((1, 2, 1), intents[:3], strict=True):
                builder.set(1.0, agent, intent)
        builder.set(1.0, 2, intents[3])  # set after, at the same time: wins
    a, b = one_by_one.build(), at_once.build()
    assert a.change_times == b.change_times == (1.0, 2.0)
    for t in (1.0, 2.0):
        assert dict(a.intents(t)) == dict(b.intents(t))
    assert dict(b.intents(1.0)) == {1: intents[2], 2: intents[3]}


def test_set_many_refuses_what_set_refuses() -> None:
    builder = TimelineBuilder([1, 2])
    with pytest.raises(ValueError, match="intent time must be a finite time >= 0 s, got nan"):
        builder.set_many(math.nan, (1,), (Intent(),))
    with pytest.raises(ValueError, match="agents and intents must have the same length, got 2"):
        builder.set_many(0.0, (1, 2), (Intent(),))
    with pytest.raises(ValueError, match=r"agent 5 is not on the stage \(ids \[1, 2\]\)"):
        builder.check_agents([1, 5])


def test_a_conversation_draws_the_same_stream_whatever_the_head_noise() -> None:
    on_target, _, rng_on = _talk(0.0)
    off_target, _, rng_off = _talk(0.3)
    assert on_target == off_target
    assert rng_on.bit_generator.state == rng_off.bit_generator.state


def test_drawing_among_one_draws_nothing() -> None:
    # A conversation of two skips ``integers(1)``: the stream is the same only while numpy
    # draws no bits for a range of one value.
    rng = np.random.default_rng(11)
    rng.integers(5)  # half of a 64-bit draw kept for the next bounded integer
    before = rng.bit_generator.state
    assert int(rng.integers(1)) == 0
    assert rng.bit_generator.state == before


def test_gazes_on_target_look_at_the_speaker_and_the_speaker_at_a_listener() -> None:
    turns, builder, _ = _talk(0.0)
    timeline = builder.build()
    for t, speaker in turns:
        intents = timeline.intents(t)
        for m in (1, 2, 3, 4):
            if m == speaker:
                assert intents[m].gaze_agent in {1, 2, 3, 4} - {speaker}
            else:
                assert intents[m].gaze_agent == speaker
            assert intents[m].gaze_point is None


def test_gazes_off_target_keep_the_targets_distance() -> None:
    turns, builder, _ = _talk(0.3)
    timeline = builder.build()
    for t, speaker in turns:
        intents = timeline.intents(t)
        for k, m in enumerate((1, 2, 3, 4)):
            assert intents[m].gaze_agent is None
            if m == speaker:
                continue
            head, target = PLACES[k], PLACES[speaker - 1]
            reach = max(float(np.hypot(*(target - head))), 0.5)
            assert float(np.hypot(*(np.array(intents[m].gaze_point) - head))) == pytest.approx(
                reach, abs=1e-12
            )
            # The standing part is the checked intent's.
            assert intents[m].goal == (float(head[0]), float(head[1]))
            assert intents[m].face_yaw == float(FACINGS[k])


def test_separate_leaves_places_far_enough_apart_and_parts_the_others() -> None:
    rng = np.random.default_rng(3)
    apart = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert np.array_equal(separate(apart, spacing=0.63), apart)
    for _ in range(200):
        places = rng.normal(size=(6, 2)) * 0.4
        moved = separate(places, spacing=0.63, iterations=200)
        gaps = np.hypot(*(moved[:, None, :] - moved[None, :, :]).transpose(2, 0, 1))
        assert gaps[np.triu_indices(6, 1)].min() >= 0.63 - 1e-9
        assert np.array_equal(places, separate(places, spacing=0.0))  # nothing to part


@pytest.mark.parametrize("enabled", [True, False], ids=["collector-on", "collector-off"])
def test_making_a_scenario_leaves_the_garbage_collector_as_it_was(enabled: bool) -> None:
    was = gc.isenabled()
    try:
        gc.enable() if enabled else gc.disable()
        scenarios.make("mingle", seed=1, duration=5.0)
        assert gc.isenabled() is enabled
        with pytest.raises(ValueError, match="no free floor"):  # failing inside the factory
            scenarios.make("mingle", seed=1, people=8, room_side=4.0)
        assert gc.isenabled() is enabled
    finally:
        gc.enable() if was else gc.disable()

"""`scenarios.Intent`: what it accepts, how it normalises it, and what it refuses (the message
names the field, what was expected and what came)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from scenarios import Intent


def test_default_intent_stands_still() -> None:
    intent = Intent()
    assert (intent.goal, intent.speed, intent.present) == (None, 1.2, True)
    assert intent == Intent(None, 1.2, None, None, None, None, None, True, None)


def test_values_are_normalised_to_python_types() -> None:
    intent = Intent(
        goal=np.array([1, 2]),
        speed=np.float64(0.8),
        face_yaw=np.float32(0.5),
        gaze_agent=np.int64(3),
        present=1,
        appear_at=[0, 1.5],
    )
    assert intent.goal == (1.0, 2.0) and type(intent.goal[0]) is float
    assert type(intent.speed) is float and intent.speed == pytest.approx(0.8)
    assert type(intent.face_yaw) is float
    assert type(intent.gaze_agent) is int and intent.gaze_agent == 3
    assert intent.present is True
    assert intent.appear_at == (0.0, 1.5)


def test_intent_is_a_frozen_value() -> None:
    intent = Intent(goal=(1.0, 2.0), face_point=(0.0, 0.0), gaze_point=(3.0, 4.0))
    assert intent == Intent(goal=(1.0, 2.0), face_point=(0.0, 0.0), gaze_point=(3.0, 4.0))
    assert hash(intent) == hash(
        Intent(goal=(1.0, 2.0), face_point=(0.0, 0.0), gaze_point=(3.0, 4.0))
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        intent.speed = 2.0  # type: ignore[misc]
    faster = dataclasses.replace(intent, speed=2)
    assert type(faster.speed) is float and faster.goal == intent.goal
    with pytest.raises(ValueError, match="at most one of face_yaw, face_point"):
        dataclasses.replace(intent, face_yaw=0.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        pytest.param(
            {"goal": (1.0, math.nan)}, r"Intent.goal must be a finite \(x, y\)", id="goal-nan"
        ),
        pytest.param(
            {"goal": (1.0, 2.0, 3.0)}, r"Intent.goal must be a finite \(x, y\)", id="goal-3d"
        ),
        pytest.param({"goal": "here"}, r"Intent.goal must be \(x, y\) in metres", id="goal-text"),
        pytest.param(
            {"face_point": (math.inf, 0.0)}, r"Intent.face_point must be", id="face-point"
        ),
        pytest.param({"gaze_point": (0.0,)}, r"Intent.gaze_point must be", id="gaze-point"),
        pytest.param({"appear_at": (0.0, math.nan)}, r"Intent.appear_at must be", id="appear-at"),
        pytest.param(
            {"face_agent": True},
            r"Intent.face_agent must be an agent id \(int\) or None, got True",
            id="face-agent-bool",
        ),
        pytest.param(
            {"gaze_agent": 1.0},
            r"Intent.gaze_agent must be an agent id \(int\) or None, got 1.0",
            id="gaze-agent-float",
        ),
        pytest.param(
            {"speed": 0.0},
            r"Intent.speed must be positive and finite \(m/s\), got 0.0",
            id="speed-zero",
        ),
        pytest.param(
            {"speed": -1},
            r"Intent.speed must be positive and finite \(m/s\), got -1",
            id="speed-negative",
        ),
        pytest.param(
            {"speed": math.inf}, r"Intent.speed must be positive and finite", id="speed-inf"
        ),
        pytest.param(
            {"speed": math.nan}, r"Intent.speed must be positive and finite", id="speed-nan"
        ),
        pytest.param(
            {"face_yaw": math.nan},
            r"Intent.face_yaw must be finite \(radians\), got nan",
            id="yaw-nan",
        ),
        pytest.param(
            {"face_yaw": 0.0, "face_agent": 2},
            r"at most one of face_yaw, face_point, face_agent, got \['face_yaw', 'face_agent'\]",
            id="two-faces",
        ),
        pytest.param(
            {"face_point": (0.0, 0.0), "face_agent": 2},
            r"got \['face_point', 'face_agent'\]",
            id="point-and-agent",
        ),
        pytest.param(
            {"face_yaw": 0.0, "face_point": (0.0, 0.0), "face_agent": 2},
            r"got \['face_yaw', 'face_point', 'face_agent'\]",
            id="three-faces",
        ),
        pytest.param(
            {"gaze_point": (0.0, 0.0), "gaze_agent": 2},
            r"at most one of gaze_point, gaze_agent, got both",
            id="two-gazes",
        ),
    ],
)
def test_bad_intents_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Intent(**kwargs)


def test_looking_at_is_the_intent_made_with_that_gaze() -> None:
    standing = Intent(goal=(1.0, 2.0), speed=0.8, face_yaw=0.5)
    by_agent = standing.looking_at(agent=np.int64(3))
    assert by_agent == Intent(goal=(1.0, 2.0), speed=0.8, face_yaw=0.5, gaze_agent=3)
    assert type(by_agent.gaze_agent) is int
    by_point = by_agent.looking_at(point=np.array([4, 5]))
    assert by_point == Intent(goal=(1.0, 2.0), speed=0.8, face_yaw=0.5, gaze_point=(4.0, 5.0))
    assert standing.gaze_agent is None  # the original is left as it was
    with pytest.raises(ValueError, match="at most one of gaze_point, gaze_agent"):
        standing.looking_at(agent=3, point=(0.0, 0.0))
    with pytest.raises(ValueError, match=r"Intent.gaze_point must be a finite \(x, y\)"):
        standing.looking_at(point=(math.nan, 0.0))
    with pytest.raises(ValueError, match="Intent.gaze_agent must be an agent id"):
        standing.looking_at(agent=True)

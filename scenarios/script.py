"""The vocabulary of scripted behaviour: what an agent wants (`Intent`) and what a script is.

* `Intent` (frozen, per agent): where to walk (``goal``, at ``speed``), which way to face once
  there or while standing (``face_yaw``, ``face_point`` or ``face_agent``), where to look
  (``gaze_point`` or ``gaze_agent``), whether to be in the room (``present``, entering at
  ``appear_at``). An agent keeps its last intent until it gets a new one; the default `Intent()`
  is "stand where you are, keep your facing, look ahead".
* `Script` (protocol): ``intents(t) -> Mapping[agent_id, Intent]`` (agents left out keep their
  last intent) and ``groups(t) -> groups or None`` (the F-formations the script declares;
  ``None`` means "not annotated"). Both are pure functions of time.

Nothing here knows about MuJoCo: the world (`sim.world.World`) samples a script and moves the
agents.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["WALK_SPEED_M_S", "Intent", "Point", "Script"]

WALK_SPEED_M_S = 1.2  # m/s, default preferred walking speed

Point = tuple[float, float]


def _point(name: str, value: Any) -> Point | None:
    if value is None:
        return None
    if type(value) is tuple and len(value) == 2:
        x, y = value
        if type(x) is float and type(y) is float and math.isfinite(x) and math.isfinite(y):
            return value  # the common case, without a round trip through numpy
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"Intent.{name} must be (x, y) in metres or None, got {value!r}") from exc
    if array.shape != (2,) or not np.all(np.isfinite(array)):
        raise ValueError(f"Intent.{name} must be a finite (x, y) in metres or None, got {value!r}")
    return (float(array[0]), float(array[1]))


def _agent_id(name: str, value: Any) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"Intent.{name} must be an agent id (int) or None, got {value!r}")
    return int(value)


@dataclass(frozen=True, init=False)
class Intent:
    """What one agent wants at one time.

    Attributes:
        goal: (x, y) to walk to, metres; ``None`` to stay where it is.
        speed: preferred walking speed, m/s (capped by the agent's limits).
        face_yaw: body yaw to take when standing (or on arrival), radians.
        face_point: (x, y) to face when standing, metres.
        face_agent: id of an agent to face when standing. At most one ``face_*`` is given;
            with none, the agent keeps its facing.
        gaze_point: (x, y) to look at, metres.
        gaze_agent: id of an agent to look at. At most one ``gaze_*`` is given; with none, the
            head looks straight ahead. A target beyond the head's limit turns the standing body.
        present: whether the agent is in the room (the robot always is).
        appear_at: (x, y) where the agent enters when it becomes present; ``None`` means where
            it left (or its start position). It enters as soon as that spot is free.
    """

    goal: Point | None = None
    speed: float = WALK_SPEED_M_S
    face_yaw: float | None = None
    face_point: Point | None = None
    face_agent: int | None = None
    gaze_point: Point | None = None
    gaze_agent: int | None = None
    present: bool = True
    appear_at: Point | None = None

    def __init__(
        self,
        goal: Point | None = None,
        speed: float = WALK_SPEED_M_S,
        face_yaw: float | None = None,
        face_point: Point | None = None,
        face_agent: int | None = None,
        gaze_point: Point | None = None,
        gaze_agent: int | None = None,
        present: bool = True,
        appear_at: Point | None = None,
    ) -> None:
        # Every field checked (and normalised) once, then all set at once: scripts make
        # thousands of intents per episode, and the frozen dataclass's own __init__ and a
        # __post_init__ setting fields one by one cost several times this.
        if goal is not None:
            goal = _point("goal", goal)
        if face_point is not None:
            face_point = _point("face_point", face_point)
        if gaze_point is not None:
            gaze_point = _point("gaze_point", gaze_point)
        if appear_at is not None:
            appear_at = _point("appear_at", appear_at)
        if face_agent is not None and type(face_agent) is not int:
            face_agent = _agent_id("face_agent", face_agent)
        if gaze_agent is not None and type(gaze_agent) is not int:
            gaze_agent = _agent_id("gaze_agent", gaze_agent)
        if type(speed) is not float or not 0.0 < speed < math.inf:
            given = speed
            speed = float(speed)
            if not (math.isfinite(speed) and speed > 0.0):
                raise ValueError(f"Intent.speed must be positive and finite (m/s), got {given!r}")
        if face_yaw is not None:
            given = face_yaw
            face_yaw = float(face_yaw)
            if not math.isfinite(face_yaw):
                raise ValueError(f"Intent.face_yaw must be finite (radians), got {given!r}")
        if (face_yaw is not None) + (face_point is not None) + (face_agent is not None) > 1:
            faces = [
                name
                for name, value in (
                    ("face_yaw", face_yaw),
                    ("face_point", face_point),
                    ("face_agent", face_agent),
                )
                if value is not None
            ]
            raise ValueError(
                f"Intent takes at most one of face_yaw, face_point, face_agent, got {faces}"
            )
        if gaze_point is not None and gaze_agent is not None:
            raise ValueError("Intent takes at most one of gaze_point, gaze_agent, got both")
        if type(present) is not bool:
            present = bool(present)
        self.__dict__.update(
            goal=goal,
            speed=speed,
            face_yaw=face_yaw,
            face_point=face_point,
            face_agent=face_agent,
            gaze_point=gaze_point,
            gaze_agent=gaze_agent,
            present=present,
            appear_at=appear_at,
        )

    def looking_at(self, *, agent: int | None = None, point: Point | None = None) -> Intent:
        """This intent, looking at ``agent`` or at ``point`` instead: what
        ``Intent(..., gaze_agent=agent, gaze_point=point)`` with this intent's other fields
        makes, with only the gaze checked (the other fields were, when this one was made).
        Conversations change a standing member's gaze at every turn."""
        if agent is not None:
            if type(agent) is not int:
                agent = _agent_id("gaze_agent", agent)
            if point is not None:
                raise ValueError("Intent takes at most one of gaze_point, gaze_agent, got both")
        elif point is not None:
            point = _point("gaze_point", point)
        looking = object.__new__(Intent)
        looking.__dict__.update(self.__dict__, gaze_agent=agent, gaze_point=point)
        return looking


@runtime_checkable
class Script(Protocol):
    """Scripted behaviour: pure functions of time (seconds from the start of the run)."""

    def intents(self, t: float) -> Mapping[int, Intent]:
        """New intents by agent id; agents left out keep their last intent."""
        ...

    def groups(self, t: float) -> Sequence[Sequence[int]] | None:
        """The F-formations the script declares at ``t`` (disjoint groups of agent ids)."""
        ...

"""A scenario, made: its stage, its whole script, the groups it plans, its natural length."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from scenarios.stage import Stage
from scenarios.timeline import PlannedGroup, ScenarioEvent, Timeline
from scenarios.truth import GroundTruth

__all__ = ["Scenario", "check_option"]


@dataclass(frozen=True, eq=False)
class Scenario:
    """One scenario drawn with one seed: everything the simulator needs to enact it.

    Attributes:
        name: the registered name, e.g. ``"word-improv"``.
        seed: the seed it was drawn with.
        stage: the room, the people, the robot.
        timeline: the script (`scenarios.script.Script`): intents and planned groups by time.
        duration: natural length of the episode, seconds.
        description: one line.
        options: every option's value (defaults included), JSON-ready; the registry records
            them (`scenarios.register`), the factory need not.
    """

    name: str
    seed: int
    stage: Stage
    timeline: Timeline
    duration: float
    description: str = ""
    options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "options", MappingProxyType(dict(self.options)))
        duration = float(self.duration)
        if not duration > 0.0:
            raise ValueError(f"{self.name}: duration must be > 0 seconds, got {duration}")
        object.__setattr__(self, "duration", duration)

    @property
    def script(self) -> Timeline:
        """The `scenarios.script.Script` the world samples."""
        return self.timeline

    @property
    def plan(self) -> tuple[PlannedGroup, ...]:
        return self.timeline.plan

    @property
    def events(self) -> tuple[ScenarioEvent, ...]:
        return self.timeline.events

    def ground_truth(self, ids: Sequence[int] | None = None) -> GroundTruth:
        """A fresh `GroundTruth` for this scenario's plan over agents ``ids`` (default: the
        stage's, people then robot)."""
        return GroundTruth(self.plan, self.stage.ids if ids is None else ids)


def check_option(
    scenario: str,
    name: str,
    value: float,
    *,
    low: float | None = None,
    high: float | None = None,
    unit: str = "",
    above: bool = False,
) -> None:
    """`ValueError` naming ``scenario``'s option ``name`` unless ``low <= value <= high``
    (``low < value`` with ``above``)."""
    too_low = low is not None and (value <= low if above else value < low)
    too_high = high is not None and value > high
    if too_low or too_high:
        left = "(" if above else "["
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        unit = f" {unit}" if unit else ""
        raise ValueError(
            f"{scenario}: option {name} must be within {left}{lo}, {hi}]{unit}, got {value!r}"
        )

"""Scripted changes of a group: a latecomer joins, a member drifts away, two groups merge.

The HRI scenes and the party take the same three options for them (each scenario declares
them in its signature with the types below; their help is `CHANGE_OPTIONS`):

* ``event_rate``: scripted changes per minute (0, the default: none, the scene as it always
  was). The changes come as a Poisson process of this rate, each waiting for the one before
  it to be over (the latecomer at their place): the gap to the next is the longer of an
  exponential draw and what the last change still needs.
* ``event_kinds``: which changes are scripted, ``"mixed"`` (each drawn among those the scene
  can play at that moment) or only ``"join"``, ``"leave"`` or ``"merge"``.
* ``approach_speed``: how fast a latecomer, or a group walking over to merge, walks up, m/s.

**How the ground truth follows the script** (`scenarios.truth`). The group as it was stays
recorded until the change has happened; the group that continues it names its newcomers
(`scenarios.timeline.PlannedGroup.newcomers`):

* **join**: a latecomer has joined in the first frame in which they stand at their place in
  the circle (within `scenarios.truth.PLACE_TOLERANCE_M`, facing their planned way within
  `scenarios.truth.FACING_TOLERANCE_RAD`); the members make room just before they arrive and
  stay in the group while they do.
* **leave**: a member drifting away has left in the first frame at or after they set off; the
  others stay where they stood, still a group.
* **merge**: a group (a pair who met first) walks over to the other, which makes room; the
  groups have merged in the first frame in which every member of the walking group stands at
  their place. Until then both groups are recorded, the walking one as a group on its way.

`reform.group_events` on the frames gives ``joins``, ``leaves`` and ``merges`` at these frames.
A change the scene cannot play when its time comes (nobody left to join, a pair that would
dissolve, no room in the group) is drawn as another kind under ``"mixed"`` and skipped
otherwise.
"""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Annotated, Literal

import numpy as np

from scenarios.registry import Range

__all__ = [
    "CHANGE_KINDS",
    "CHANGE_OPTIONS",
    "JOIN",
    "LEAVE",
    "MERGE",
    "ApproachSpeed",
    "EventKinds",
    "EventRate",
    "draw_kind",
    "next_change",
]

JOIN, LEAVE, MERGE = "join", "leave", "merge"
CHANGE_KINDS = (JOIN, LEAVE, MERGE)  # also the names of the scenario's log events
MAX_EVENT_RATE_PER_MIN = 20.0  # changes per minute: one every 3 s, about a walk-up's length

EventRate = Annotated[float, Range(0.0, MAX_EVENT_RATE_PER_MIN, unit="per minute")]
"""Scripted changes per minute: 0 (none) to :data:`MAX_EVENT_RATE_PER_MIN`."""
EventKinds = Literal["mixed", "join", "leave", "merge"]
"""Which changes are scripted."""
ApproachSpeed = Annotated[float, Range(0.7, 1.5, unit="m/s")]
"""How fast people walk up to a group, m/s: 0.7 (a slow approach: slower, the motion's
keeping of personal space can hold a walker off a group) to 1.5 (a
hurry; people's top speed)."""

CHANGE_OPTIONS = MappingProxyType(
    {
        "event_rate": "scripted changes per minute: latecomers joining, members drifting "
        "away, groups merging (0: none); a Poisson process, each change waiting for the one "
        "before to be over.",
        "event_kinds": "which changes are scripted: mixed (drawn among those possible), or "
        "only join, leave or merge.",
        "approach_speed": "how fast a latecomer, or a group walking over to merge, walks up, m/s.",
    }
)
"""The help of the scripted changes' options, for every scenario that declares them."""


def next_change(rng: np.random.Generator, rate: float, *, ready: float, last: float) -> float:
    """When the next scripted change comes, seconds: ``last`` (the previous change's time) plus
    an exponential gap of mean ``60 / rate``, but not before ``ready`` (when the scene can play
    it); ``inf`` when ``rate`` is 0."""
    if rate <= 0.0:
        return math.inf
    return max(last + float(rng.exponential(60.0 / rate)), ready)


def draw_kind(rng: np.random.Generator, kinds: str, possible: dict[str, bool]) -> str | None:
    """The kind of the next change: ``kinds`` itself when the scene can play it, or (with
    ``"mixed"``) one drawn evenly among those it can play (``possible``); None when none."""
    if kinds != "mixed":
        return kinds if possible.get(kinds, False) else None
    options = [k for k in CHANGE_KINDS if possible.get(k, False)]
    if not options:
        return None
    return options[int(rng.integers(len(options)))]

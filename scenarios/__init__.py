"""scenarios: scripted social scenes as data and pure functions of time and a random generator.

Registered scenarios (``make(name, seed=..., **options)``, ``names()``, ``names(tag=...)``,
``options(name)``), each option written once in its factory's signature (`register`):

* ``hri-conversation``, ``hri-robot-excluded``, ``hri-passing``: the REFORM paper's
  proof-of-concept scenes with the Directions Robot (`scenarios.hri`), the fixed set
  ``PAPER_HRI_SCENES`` (a curated set: a new scenario tagged ``hri`` does not join it);
* ``word-improv``: the Babble game (`scenarios.word_improv`);
* ``mingle``: a SALSA-like party (`scenarios.mingle`);
* ``mingle-randomised``: mingling with every shape parameter drawn from wide ranges, for domain
  randomisation (`scenarios.randomisation`);
* ``concourse``: a station hall of hundreds to thousands: walkers crossing between entrances,
  a queue, and groups standing aside in the corners (`scenarios.concourse`).

A scenario is made from its seed alone: every random choice is drawn when it is made, into a
`Timeline` (intents by time, the groups it plans, events), so the world samples it with a
lookup. It describes its scene as plain data (`Stage`); the simulator (`sim.episode`) builds it.

**Ground-truth rule.** A script plans each F-formation: its members, each member's place on the
o-space circle and the way each is to face (toward the centre, with the scenario's noise), when
they are sent there and when the first of them is sent away. A group *starts* in the first frame
in which every member has arrived: present, within `PLACE_TOLERANCE_M` (0.25 m) of its place
and facing within `FACING_TOLERANCE_RAD` (30 degrees) of its planned way. Walking up to a group
is not yet being in it. A group *ends* when its first member leaves its place, or when a newer
planned group sharing members forms (someone joined, groups merged, the circle re-formed after a
shuffle), which replaces it from that frame on. A group that continues another after a
scripted change (`scenarios.changes`: a latecomer joins, a member drifts away, a group walks
over to merge) starts once its newcomers have taken their places, the members it keeps being
still together; until then the group as it was is recorded. Everyone else is a singleton.
`GroundTruth` applies the rule to the poses the world produces (`sim.episode` does this for
every episode).
"""

from __future__ import annotations

from scenarios import (  # noqa: F401  (registration)
    concourse,
    hri,
    mingle,
    randomisation,
    registry,
    word_improv,
)
from scenarios.changes import CHANGE_KINDS
from scenarios.hri import PAPER_HRI_SCENES
from scenarios.registry import *  # noqa: F403  (its public names, listed once in its __all__)
from scenarios.scenario import Scenario
from scenarios.script import WALK_SPEED_M_S, Intent, Script
from scenarios.stage import PLANNING_RADIUS_M, Furniture, RobotPlace, Role, Stage
from scenarios.timeline import PlannedGroup, ScenarioEvent, Timeline, TimelineBuilder
from scenarios.truth import FACING_TOLERANCE_RAD, PLACE_TOLERANCE_M, GroundTruth

__all__ = [
    *registry.__all__,
    "CHANGE_KINDS",
    "FACING_TOLERANCE_RAD",
    "PAPER_HRI_SCENES",
    "PLACE_TOLERANCE_M",
    "PLANNING_RADIUS_M",
    "WALK_SPEED_M_S",
    "Furniture",
    "GroundTruth",
    "Intent",
    "PlannedGroup",
    "RobotPlace",
    "Role",
    "Scenario",
    "ScenarioEvent",
    "Script",
    "Stage",
    "Timeline",
    "TimelineBuilder",
]

"""Who is on stage and where they start: the scene a scenario asks for, as plain data.

A `Stage` names the room, the people (`Role`: id, start pose, height, shoulder width, whether
present at the start, what part they play) and, optionally, where the Directions Robot stands
(`RobotPlace`). It holds no MuJoCo and checks nothing physical: the simulator turns it into its
own scene description (`sim.episode.scene_spec`), which validates sizes, overlaps and room
capacity in one place.

Scenarios plan with `PLANNING_RADIUS_M`, the largest body radius any person they cast can have
(a person's body disc encloses the arms: 0.64 x shoulder width), so that the places they pick
for people standing side by side never overlap. A scenario may give people a smaller body disc
(`Role.radius`, at least `MIN_BODY_RADIUS_M`) so that they can stand shoulder to shoulder: closer
than the disc that encloses the arms, arms and noses may then touch.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "PERSON_HEIGHT_M",
    "PERSON_WIDTH_M",
    "PLANNING_RADIUS_M",
    "FURNITURE_KINDS",
    "MIN_BODY_RADIUS_M",
    "ROBOT_RADIUS_M",
    "SPACING_M",
    "Furniture",
    "RobotPlace",
    "Role",
    "Stage",
]

PERSON_HEIGHT_M = (1.55, 1.92)  # metres, range of heights scenarios cast
PERSON_WIDTH_M = (0.40, 0.46)  # metres, range of shoulder widths scenarios cast
PLANNING_RADIUS_M = 0.30  # metres, >= 0.64 x the widest shoulders cast (a body disc)
ROBOT_RADIUS_M = 0.28  # metres, the robot's base disc (planning only)
CLEARANCE_M = 0.03  # metres, gap the motion keeps between two bodies (covers idle sway)
SPACING_M = 2 * PLANNING_RADIUS_M + CLEARANCE_M  # metres, closest two people's places may be
MIN_BODY_RADIUS_M = 0.20  # metres, smallest body disc a scenario may give (shoulder to shoulder)
FURNITURE_KINDS = ("table", "bar", "poster")  # what a scene may furnish a room with


@dataclass(frozen=True)
class Furniture:
    """A static object people stand around or along (it does not move, and people walking
    plan around the floor it takes only through the scenario's plan).

    Attributes:
        kind: one of `FURNITURE_KINDS`: a round ``"table"``, a ``"bar"`` counter, a
            ``"poster"`` board.
        position: (x, y) of its centre on the floor, metres.
        size: (length along its yaw, depth across it, height), metres; a table's length is
            its diameter.
        yaw: direction of its length, radians.
    """

    kind: str
    position: tuple[float, float]
    size: tuple[float, float, float]
    yaw: float = 0.0


@dataclass(frozen=True)
class Role:
    """One person of a scenario.

    Attributes:
        id: the person's id in every Frame.
        position: (x, y) start position, metres.
        yaw: start body yaw, radians.
        height: metres.
        width: shoulder width, metres.
        present: whether the person is in the room at the start.
        part: what the person plays (``"player"``, ``"moderator"``, ``"guest"``, ...).
        radius: body disc radius, metres, or ``None`` for the simulator's own (a disc enclosing
            the arms, 0.64 x width); smaller lets people stand shoulder to shoulder.
    """

    id: int
    position: tuple[float, float]
    yaw: float = 0.0
    height: float = 1.75
    width: float = 0.44
    present: bool = True
    part: str = "person"
    radius: float | None = None


@dataclass(frozen=True)
class RobotPlace:
    """Where the Directions Robot starts.

    Attributes:
        id: the robot's id in every Frame.
        position: (x, y), metres.
        yaw: radians.
    """

    id: int = 0
    position: tuple[float, float] = (0.0, 0.0)
    yaw: float = 0.0


@dataclass(frozen=True)
class Stage:
    """The room, the people and the robot of a scenario.

    Attributes:
        room: (x extent, y extent) of the floor, metres, centred on the origin.
        people: the people, in the order they appear in every Frame.
        robot: where the robot starts, or ``None`` for people only.
        furniture: tables, bar counters and posters standing in the room.
    """

    room: tuple[float, float]
    people: tuple[Role, ...]
    robot: RobotPlace | None = None
    furniture: tuple[Furniture, ...] = ()

    @property
    def ids(self) -> tuple[int, ...]:
        """Every agent id: people in order, then the robot."""
        robot = () if self.robot is None else (self.robot.id,)
        return tuple(p.id for p in self.people) + robot

    def part_of(self, agent_id: int) -> str:
        """What agent ``agent_id`` plays (``"robot"`` for the robot)."""
        if self.robot is not None and agent_id == self.robot.id:
            return "robot"
        for person in self.people:
            if person.id == agent_id:
                return person.part
        raise KeyError(f"no agent with id {agent_id} on the stage (ids {list(self.ids)})")

"""A scenario's whole script, drawn once: intents by time, planned groups, events.

A scenario draws everything random when it is made (from its generator) and writes it into a
`TimelineBuilder`: new intents for agents at given times, the groups it means to form
(`PlannedGroup`: members, their places on the o-space circle and the way each faces), and
`ScenarioEvent`s for the logs. `TimelineBuilder.build` freezes this into a `Timeline`, the
`scenarios.script.Script` the world samples: ``intents(t)`` is a binary search into the
change times, every agent's intents then written out from the nearest checkpoint (the same
mapping object is returned until something changes, so the world skips unchanged intents),
``groups(t)`` lists the planned groups whose window holds ``t``.
"""

from __future__ import annotations

import bisect
import math
import operator
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from scenarios.script import Intent

__all__ = ["PlannedGroup", "ScenarioEvent", "Timeline", "TimelineBuilder"]

_time = operator.itemgetter(0)
_all_true = np.logical_and.reduce  # ndarray.all, without its Python wrapper

_TIME_SLACK_S = 1e-9  # seconds: a change at t applies to samples at t despite rounding
CHECKPOINT_CHANGES = 64  # a built timeline writes every agent's intents out once per this many
# changes (memory: agents x changes / 64 entries, rather than agents x changes)


@dataclass(frozen=True)
class ScenarioEvent:
    """Something the script makes happen, for the logs.

    Attributes:
        time: seconds from the start.
        kind: short name, e.g. ``"turn"``, ``"shuffle"``, ``"elimination"``, ``"join"``.
        detail: one line of detail.
    """

    time: float
    kind: str
    detail: str = ""

    @property
    def text(self) -> str:
        return f"{self.kind}: {self.detail}" if self.detail else self.kind


@dataclass(frozen=True, eq=False, init=False)
class PlannedGroup:
    """An F-formation the script means to form.

    Attributes:
        members: agent ids, in order around the circle.
        places: (k, 2) where each member is to stand, metres.
        facings: (k,) the body yaw each member is to take there, radians.
        centre: (2,) the o-space centre, metres.
        start: when the members are sent to their places, seconds.
        end: when the first member is sent away, seconds (``inf``: never); for a group that a
            newer one continues (someone joins it, it merges), when that newer group ends: it
            is recorded until the newer group starts (`scenarios.truth`).
        newcomers: for a group that continues an older one (someone joined or left it, or a
            group merged into it), the members new to it, who must take their places before it
            starts (``()``: someone left, nobody is new); ``None``: a group of its own, every
            member must arrive.
    """

    members: tuple[int, ...]
    places: np.ndarray
    facings: np.ndarray
    centre: np.ndarray
    start: float
    end: float = math.inf
    newcomers: tuple[int, ...] | None = None

    def __init__(
        self,
        members: Sequence[int],
        places: np.ndarray,
        facings: np.ndarray,
        centre: np.ndarray,
        start: float,
        end: float = math.inf,
        newcomers: Sequence[int] | None = None,
    ) -> None:
        # Every field checked (and copied) once, then all set at once: a party plans hundreds
        # of groups, and the frozen dataclass's own __init__ and a __post_init__ setting fields
        # one by one cost an eighth more.
        members = tuple(int(m) for m in members)
        k = len(members)
        if k < 2 or len(set(members)) != k:
            raise ValueError(f"PlannedGroup.members must be >= 2 distinct ids, got {members}")
        arrays = {}
        for name, value, shape in (
            ("places", places, (k, 2)),
            ("facings", facings, (k,)),
            ("centre", centre, (2,)),
        ):
            array = np.array(value, dtype=np.float64)
            if array.shape != shape or not _all_true(np.isfinite(array), axis=None):
                raise ValueError(f"PlannedGroup.{name} must be finite with shape {shape}")
            array.setflags(write=False)
            arrays[name] = array
        if not end > start:
            raise ValueError(
                f"PlannedGroup {members}: end must come after start, got {start} -> {end}"
            )
        if newcomers is not None:
            newcomers = tuple(int(m) for m in newcomers)
            if len(set(newcomers)) != len(newcomers) or not set(newcomers) <= set(members):
                raise ValueError(
                    f"PlannedGroup {members}: newcomers must be distinct members, got {newcomers}"
                )
        self.__dict__.update(
            members=members,
            **arrays,
            start=float(start),
            end=float(end),
            newcomers=newcomers,
        )


class Timeline:
    """A precomputed script: intents by time, planned groups, events (see the module doc).

    Args:
        times: increasing change times, seconds.
        snapshots: the full intent of every agent from each change time on (same length).
        plan: the planned groups, by start time.
        events: the scenario's events, by time.
    """

    def __init__(
        self,
        times: Sequence[float],
        snapshots: Sequence[Mapping[int, Intent]],
        plan: Sequence[PlannedGroup],
        events: Sequence[ScenarioEvent],
    ) -> None:
        if len(times) != len(snapshots):
            raise ValueError(
                f"times and snapshots must have the same length, got {len(times)} and "
                f"{len(snapshots)}"
            )
        self._times = [float(t) for t in times]
        self._snapshots: tuple[Mapping[int, Intent], ...] | None = tuple(snapshots)
        self._deltas: tuple[dict[int, Intent], ...] = ()
        self._checkpoints: tuple[dict[int, Intent], ...] = ()
        self._last: tuple[int, Mapping[int, Intent]] = (-1, MappingProxyType({}))
        self._empty: Mapping[int, Intent] = MappingProxyType({})
        self.plan = tuple(sorted(plan, key=lambda g: g.start))
        self.events = tuple(sorted(events, key=lambda e: e.time))
        self._starts = [g.start for g in self.plan]

    @classmethod
    def _of_changes(
        cls,
        times: Sequence[float],
        deltas: Sequence[dict[int, Intent]],
        plan: Sequence[PlannedGroup],
        events: Sequence[ScenarioEvent],
    ) -> Timeline:
        """A timeline kept as the intents that change at each time (``deltas``), with every
        agent's intents written out only every `CHECKPOINT_CHANGES` changes: a crowd's script
        changes someone's intent thousands of times, and a full snapshot per change would grow
        as agents times changes. ``intents`` writes a snapshot out when it is asked for."""
        timeline = cls(times, [{}] * len(times), plan, events)
        timeline._snapshots = None
        timeline._deltas = tuple(deltas)
        current: dict[int, Intent] = {}
        checkpoints = []
        for k, delta in enumerate(timeline._deltas):
            current.update(delta)
            if k % CHECKPOINT_CHANGES == 0:
                checkpoints.append(dict(current))
        timeline._checkpoints = tuple(checkpoints)
        return timeline

    def intents(self, t: float) -> Mapping[int, Intent]:
        """Every agent's intent at ``t`` (the same object until the next change)."""
        k = bisect.bisect_right(self._times, t + _TIME_SLACK_S) - 1
        if k < 0:
            return self._empty
        if self._snapshots is not None:
            return self._snapshots[k]
        last, snapshot = self._last
        if k == last:
            return snapshot
        start = k - k % CHECKPOINT_CHANGES
        if start <= last < k:  # on from the last one asked for (times asked in order)
            current = dict(snapshot)
            start = last
        else:
            current = dict(self._checkpoints[k // CHECKPOINT_CHANGES])
        for delta in self._deltas[start + 1 : k + 1]:
            current.update(delta)
        snapshot = MappingProxyType(current)
        self._last = (k, snapshot)
        return snapshot

    def groups(self, t: float) -> tuple[tuple[int, ...], ...]:
        """The planned groups whose window ``[start, end)`` holds ``t`` (walking up included;
        the episode's ground truth applies the arrival rule, see `scenarios.truth`)."""
        stop = bisect.bisect_right(self._starts, t + _TIME_SLACK_S)
        return tuple(g.members for g in self.plan[:stop] if t < g.end)

    @property
    def change_times(self) -> tuple[float, ...]:
        """When some agent's intent changes, seconds."""
        return tuple(self._times)


class TimelineBuilder:
    """Collects a scenario's intents, planned groups and events, in any order.

    Args:
        agents: every agent id of the stage (people and robot).
    """

    def __init__(self, agents: Iterable[int]) -> None:
        self._agents = tuple(int(a) for a in agents)
        self._known = set(self._agents)
        # (time, agents, their intents), as set: one entry per `set` or `set_many`
        self._changes: list[tuple[float, tuple[int, ...], tuple[Intent, ...]]] = []
        self._groups: list[dict] = []
        self._continues: list[tuple[int, ...]] = []  # per planned group, the groups it continues
        self._events: list[ScenarioEvent] = []

    def set(self, t: float, agent: int, intent: Intent) -> None:
        """From ``t`` on, ``agent`` wants ``intent`` (a later call for the same time wins)."""
        if agent not in self._known:
            raise ValueError(f"agent {agent} is not on the stage (ids {list(self._agents)})")
        if not 0.0 <= t < math.inf:  # NaN fails too
            raise ValueError(f"intent time must be a finite time >= 0 s, got {t}")
        self._changes.append((float(t), (int(agent),), (intent,)))

    def check_agents(self, agents: Iterable[int]) -> None:
        """`ValueError` naming the first of ``agents`` not on the stage."""
        agents = list(agents)
        if not self._known.issuperset(agents):
            agent = next(a for a in agents if a not in self._known)
            raise ValueError(f"agent {agent} is not on the stage (ids {list(self._agents)})")

    def set_many(self, t: float, agents: Sequence[int], intents: Sequence[Intent]) -> None:
        """From ``t`` on, each of ``agents`` wants its intent in ``intents``: `set` for each in
        turn, for agents already checked (`check_agents`) and given as ``int``."""
        if not 0.0 <= t < math.inf:  # NaN fails too
            raise ValueError(f"intent time must be a finite time >= 0 s, got {t}")
        if len(agents) != len(intents):
            raise ValueError(
                f"agents and intents must have the same length, got {len(agents)} and "
                f"{len(intents)}"
            )
        self._changes.append((float(t), tuple(agents), tuple(intents)))

    def group(
        self,
        members: Sequence[int],
        places: np.ndarray,
        facings: np.ndarray,
        centre: np.ndarray,
        *,
        start: float,
        end: float = math.inf,
        newcomers: Sequence[int] | None = None,
        continues: Sequence[int] = (),
    ) -> int:
        """Plans an F-formation; returns its handle for `end_group`.

        Args:
            newcomers: see `PlannedGroup`.
            continues: handles of the planned groups this one continues (someone joined, a
                group merged in): each is kept planned until this one ends (`build`), so that
                it is recorded until this one starts.
        """
        entry = {
            "members": tuple(int(m) for m in members),
            "places": np.asarray(places, dtype=np.float64),
            "facings": np.asarray(facings, dtype=np.float64),
            "centre": np.asarray(centre, dtype=np.float64),
            "start": float(start),
            "end": float(end),
        }
        if newcomers is not None:
            entry["newcomers"] = tuple(int(m) for m in newcomers)
        self._groups.append(entry)
        for handle in continues:
            if not 0 <= handle < len(self._groups) - 1:
                raise ValueError(
                    f"continues names planned group {handle}, which was not planned before"
                )
        self._continues.append(tuple(int(h) for h in continues))
        return len(self._groups) - 1

    def end_group(self, handle: int, t: float) -> None:
        """The planned group ``handle`` ends at ``t`` (its first member is sent away)."""
        entry = self._groups[handle]
        entry["end"] = min(entry["end"], float(t))

    def event(self, t: float, kind: str, detail: str = "") -> None:
        self._events.append(ScenarioEvent(float(t), kind, detail))

    def build(self) -> Timeline:
        """The frozen `Timeline`."""
        self._changes.sort(key=_time)  # by time, then order of setting (the sort is stable)
        times: list[float] = []
        deltas: list[dict[int, Intent]] = []
        delta: dict[int, Intent] = {}
        last = math.nan
        for t, agents, intents in self._changes:
            if t != last:
                delta = {}
                times.append(t)
                deltas.append(delta)
                last = t
            delta.update(zip(agents, intents, strict=True))
        groups = [dict(g) for g in self._groups]
        for k in range(len(groups) - 1, -1, -1):  # the newest first: chains resolve in one pass
            for handle in self._continues[k]:
                groups[handle]["end"] = max(groups[handle]["end"], groups[k]["end"])
        plan = [PlannedGroup(**g) for g in groups if g["end"] > g["start"]]
        return Timeline._of_changes(times, deltas, plan, self._events)

"""The ground-truth rule: when a planned group becomes an F-formation, and when it stops.

A script plans groups (`scenarios.timeline.PlannedGroup`): members, their places on the o-space
circle, the way each is to face, the time they are sent there (``start``) and the time the first
of them is sent away (``end``). What the frames record follows one rule:

* **A group starts when its members have arrived**: the first frame at or after ``start`` in
  which every member is present, stands within `PLACE_TOLERANCE_M` of its place and faces within
  `FACING_TOLERANCE_RAD` of its planned facing (toward the centre, with the scenario's
  orientation noise). Walking up to a group is not yet being in it.
* **It ends when the first member leaves its place** (``end``), or when a later planned group
  sharing members with it starts (someone joined, two groups merged, a group re-formed after a
  shuffle): the newer group replaces it from the frame it forms.
* **A group that continues another** (``newcomers`` given: a latecomer joins it, a member
  drifts away, another group merges into it) starts in the first frame at or after its start
  in which its newcomers have arrived (present, at their places, facing their planned way) and
  the members it keeps are present and still recorded together in one group. The members it
  keeps need not stand at their new places yet: making room for a latecomer does not interrupt
  a conversation. A latecomer has joined when they take their place (the script keeps the
  group it continues planned until then, `PlannedGroup.end`); someone leaving is gone from the
  group in the first frame at or after they set off (``newcomers=()``: the group as it was
  ends then, the rest are a group from that frame on). When the members
  it keeps are not together (a change before it never happened: someone never got to their
  place), it starts as any group does, once every member has arrived.
* A planned group that never forms (a member blocked on the way) is never recorded; one that
  would form after a newer group sharing its members formed is dropped.

`GroundTruth` applies the rule to blocks of poses as the episode runs (state is kept between
blocks), vectorised over the frames of each block.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence

import numpy as np

from scenarios.timeline import PlannedGroup

__all__ = ["FACING_TOLERANCE_RAD", "PLACE_TOLERANCE_M", "GroundTruth"]

PLACE_TOLERANCE_M = 0.25  # metres, a member this close to its place has arrived
FACING_TOLERANCE_RAD = math.radians(30.0)  # radians, ... and faces its planned way within this

Group = tuple[int, ...]


class GroundTruth:
    """Applies the ground-truth rule to consecutive blocks of poses.

    Args:
        plan: the scenario's planned groups.
        ids: (n,) agent ids, the columns of the pose arrays.
        place_tolerance: metres.
        facing_tolerance: radians.
    """

    def __init__(
        self,
        plan: Sequence[PlannedGroup],
        ids: Sequence[int],
        *,
        place_tolerance: float = PLACE_TOLERANCE_M,
        facing_tolerance: float = FACING_TOLERANCE_RAD,
    ) -> None:
        self._plan = tuple(sorted(plan, key=lambda g: g.start))
        self._ids = tuple(int(a) for a in ids)
        column = {a: c for c, a in enumerate(self._ids)}
        self._columns = []
        for g in self._plan:
            missing = [m for m in g.members if m not in column]
            if missing:
                raise ValueError(
                    f"planned group {g.members} names agents {missing} who are not in the scene "
                    f"(ids {list(column)})"
                )
            self._columns.append(np.array([column[m] for m in g.members], dtype=np.int64))
        self._place_tol = float(place_tolerance)
        self._facing_tol = float(facing_tolerance)
        k = len(self._plan)
        self._live_from = np.full(k, math.inf)  # when each formed (inf: not yet)
        self._live_until = np.array([g.end for g in self._plan], dtype=np.float64)
        self._dropped = np.zeros(k, dtype=bool)
        self._next = 0  # plan entries before this one have been looked at

    @property
    def ids(self) -> tuple[int, ...]:
        """The agent ids, the columns of the pose arrays `update` takes."""
        return self._ids

    def update(
        self,
        time: np.ndarray,
        present: np.ndarray,
        position: np.ndarray,
        yaw: np.ndarray,
    ) -> tuple[tuple[Group, ...], ...]:
        """The F-formations of each row of a block (rows in time order, after earlier blocks).

        Args:
            time: (T,) seconds.
            present: (T, n) bool.
            position: (T, n, 2) body positions, metres.
            yaw: (T, n) body yaws, radians.

        Returns:
            T tuples of groups (each a tuple of member ids in planned order).
        """
        time = np.asarray(time, dtype=np.float64)
        rows = time.size
        if rows == 0:
            return ()
        t_last = float(time[-1])
        # (time, plan entry, candidate): the first frame each planned group may start in; a
        # group that continues another may start in any frame its newcomers have arrived in,
        # the first in which the members it keeps are still recorded together.
        arrivals: list[tuple[float, int, int]] = []
        candidates: dict[int, np.ndarray] = {}
        everyone: dict[int, np.ndarray] = {}  # ... and whether every member has arrived then
        for r in range(len(self._plan)):
            g = self._plan[r]
            if g.start > t_last + 1e-9:
                break
            if self._dropped[r] or math.isfinite(self._live_from[r]) or g.end <= time[0]:
                continue
            window = (time >= g.start - 1e-9) & (time < g.end)
            if not window.any():
                continue
            cols = self._columns[r]
            pos = position[window][:, cols]
            off = np.hypot(pos[..., 0] - g.places[:, 0], pos[..., 1] - g.places[:, 1])
            turn = np.abs(np.angle(np.exp(1j * (yaw[window][:, cols] - g.facings))))
            arrived = present[window][:, cols] & (off <= self._place_tol)
            arrived &= turn <= self._facing_tol
            if g.newcomers is None:
                hit = np.flatnonzero(arrived.all(axis=1))
                if hit.size:
                    arrivals.append((float(time[window][hit[0]]), r, 0))
                continue
            new = np.array([m in g.newcomers for m in g.members], dtype=bool)
            ok = present[window][:, cols].all(axis=1) & arrived[:, new].all(axis=1)
            times = time[window][ok]
            if times.size:
                candidates[r] = times
                everyone[r] = arrived[ok].all(axis=1)
                arrivals.append((float(times[0]), r, 0))
        heapq.heapify(arrivals)
        while arrivals:
            t_arrive, r, k = heapq.heappop(arrivals)
            if self._dropped[r] or math.isfinite(self._live_from[r]):
                continue
            if r in candidates and not (everyone[r][k] or self._kept_together(r, t_arrive)):
                if k + 1 < candidates[r].size:
                    heapq.heappush(arrivals, (float(candidates[r][k + 1]), r, k + 1))
                continue
            members = set(self._plan[r].members)
            newer_live = False
            for q in range(len(self._plan)):
                if q == r or not math.isfinite(self._live_from[q]):
                    continue
                if self._live_until[q] <= t_arrive or members.isdisjoint(self._plan[q].members):
                    continue
                if self._plan[q].start > self._plan[r].start:
                    newer_live = True
                    break
            if newer_live:
                self._dropped[r] = True
                continue
            self._live_from[r] = t_arrive
            for q in range(len(self._plan)):
                if q == r or not math.isfinite(self._live_from[q]):
                    continue
                if self._live_until[q] > t_arrive and not members.isdisjoint(self._plan[q].members):
                    self._live_until[q] = t_arrive
        out: list[list[Group]] = [[] for _ in range(rows)]
        live = np.flatnonzero((self._live_from <= t_last) & (self._live_until > time[0]))
        for r in live.tolist():
            mask = (time >= self._live_from[r]) & (time < self._live_until[r])
            members = self._plan[r].members
            for row in np.flatnonzero(mask).tolist():
                out[row].append(members)
        return tuple(tuple(groups) for groups in out)

    def _kept_together(self, r: int, t: float) -> bool:
        """Whether the members planned group ``r`` keeps (all but its newcomers) were recorded
        together in one group when ``r`` was planned, and still are at ``t`` (for a group
        someone left: until they set off); none kept: trivially."""
        g = self._plan[r]
        kept = set(g.members) - set(g.newcomers or ())
        if not kept:
            return True
        for q in range(len(self._plan)):
            live = self._live_from[q] <= t and self._live_until[q] >= g.start - 1e-9
            if q == r or not live:
                continue
            if kept <= set(self._plan[q].members):
                return True
        return False

    def formed(self) -> tuple[tuple[PlannedGroup, float, float], ...]:
        """The planned groups that formed so far, with the times they started and ended."""
        return tuple(
            (g, float(self._live_from[r]), float(self._live_until[r]))
            for r, g in enumerate(self._plan)
            if math.isfinite(self._live_from[r])
        )

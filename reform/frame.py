"""The data model: one instant of a scene (`Frame`) and an ordered sequence of them (`Dataset`).

One `Frame` type travels the whole pipeline: scenario script -> MuJoCo world -> ground truth ->
robot's sensor model -> detector -> metrics -> report. Both records are frozen dataclasses whose
arrays are read-only copies, validated at construction.

Conventions (see the project README):
  * positions are ground-plane ``(x, y)`` in metres;
  * yaws are radians, counter-clockwise from +x, wrapped to ``[-pi, pi]``;
  * groups are tuples of person ids; people named in no group are singletons.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
import numpy.typing as npt

HUMAN = "human"
ROBOT = "robot"
KINDS = (HUMAN, ROBOT)

# Tolerance on the wrapped-angle range, so that values written with a few decimals
# (Babble's -3.142) are accepted as wrapped. Radians.
_YAW_TOLERANCE_RAD = 2e-3

# Largest |x| or |y| of a position, metres (100,000 km): beyond any georeferenced coordinate (UTM
# northings reach 1e7 m), so a larger value is a corrupt number or a unit mistake; far larger
# ones overflow the classifiers' float32 features and GCFF's squared distances.
POSITION_LIMIT_M = 1e8

Group = tuple[int, ...]


def wrap_angle(theta: npt.ArrayLike) -> np.ndarray:
    """Wraps angles (radians) to ``[-pi, pi)``, elementwise, as a float64 array."""
    theta = np.asarray(theta, dtype=np.float64)
    return (theta + np.pi) % (2.0 * np.pi) - np.pi


def _readonly(array: np.ndarray) -> np.ndarray:
    array = np.array(array, copy=True, order="C")  # C order: loadmat gives Fortran order
    array.flags.writeable = False
    return array


def _float_array(name: str, value: Any, shape: tuple[int, ...]) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric with shape {shape}, got {value!r}") from exc
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {array.shape}")
    return array


def _check_extent(name: str, position: np.ndarray, ids: np.ndarray) -> None:
    beyond = np.abs(position) > POSITION_LIMIT_M  # NaN (a missing head) compares False
    if beyond.any():
        row, column = np.argwhere(beyond)[0]
        raise ValueError(
            f"{name} must be metres with |x|, |y| <= {POSITION_LIMIT_M:g}, got "
            f"{'xy'[column]} = {float(position[row, column])!r} for person {int(ids[row])}"
        )


def _check_yaw(name: str, yaw: np.ndarray) -> None:
    beyond = np.abs(yaw) > math.pi + _YAW_TOLERANCE_RAD  # NaN (a missing head) compares False
    if beyond.any():
        worst = float(yaw[np.argmax(np.where(beyond, np.abs(yaw), -1.0))])
        raise ValueError(
            f"{name} must be radians wrapped to [-pi, pi], got {worst:.6g} "
            "(wrap with reform.wrap_angle; values beyond 2*pi often mean degrees)"
        )


@dataclass(frozen=True, eq=False)
class Frame:
    """One instant of a scene: who is where, facing where, and who is in which group.

    Attributes:
        ids: (n,) int64 person ids, unique within the frame.
        kinds: n strings, each ``"human"`` or ``"robot"``.
        position: (n, 2) float64 body (torso) ground-plane position, metres. Finite, with
            ``|x|, |y| <=`` :data:`POSITION_LIMIT_M`.
        yaw: (n,) float64 body yaw, radians CCW from +x, within [-pi, pi]. Finite.
        head_position: optional (n, 2) float64 head ground-plane position, metres. A row of
            NaN means that person's head was not observed; a row is either all finite or NaN.
        head_yaw: optional (n,) float64 head yaw, radians in [-pi, pi]; NaN exactly where
            ``head_position`` is NaN. Given together with ``head_position`` or not at all.
        groups: optional ground truth: disjoint groups (tuples of ids of this frame). People in
            no group are singletons. ``None`` means the frame is not annotated.
        listed_groups: optional ground-truth F-formations exactly as the annotation lists them
            when it names people who are not in this frame (the annotators saw someone the
            tracker did not): disjoint groups of two or more ids, some of them not in ``ids``.
            Their members present in the frame must make up ``groups``' F-formations. The
            evaluation scores against them, as the field's protocol does (an absent member
            can never be detected and counts against the match); detectors, features and
            training see only ``groups``. ``None`` (the usual case): every listed member is
            present and the ground truth is ``groups``.
        time: time stamp, seconds from the start of its sequence.
        sequence: name of the recording (session, episode) the frame belongs to.
    """

    ids: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    kinds: tuple[str, ...] | None = None
    head_position: np.ndarray | None = None
    head_yaw: np.ndarray | None = None
    groups: tuple[Group, ...] | None = None
    time: float = 0.0
    sequence: str = ""
    listed_groups: tuple[Group, ...] | None = None

    def __post_init__(self) -> None:
        ids = np.asarray(self.ids)
        if ids.ndim != 1:
            raise ValueError(f"ids must have shape (n_people,), got {ids.shape}")
        if ids.size and not np.issubdtype(ids.dtype, np.integer):
            if not (np.issubdtype(ids.dtype, np.floating) and np.all(ids == np.round(ids))):
                raise ValueError(f"ids must be integers, got dtype {ids.dtype}")
        ids = ids.astype(np.int64)
        n = ids.size
        if len(set(ids.tolist())) != n:
            unique, counts = np.unique(ids, return_counts=True)
            raise ValueError(
                f"ids must be unique within a frame, got duplicates {unique[counts > 1].tolist()}"
            )
        position = _float_array("position", self.position, (n, 2))
        if not np.isfinite(position).all():
            raise ValueError("position must be finite, got NaN or inf")
        _check_extent("position", position, ids)
        yaw = _float_array("yaw", self.yaw, (n,))
        if not np.isfinite(yaw).all():
            raise ValueError("yaw must be finite, got NaN or inf")
        _check_yaw("yaw", yaw)

        kinds = tuple(HUMAN for _ in range(n)) if self.kinds is None else tuple(self.kinds)
        if len(kinds) != n:
            raise ValueError(f"kinds must have {n} entries, got {len(kinds)}")
        unknown = sorted({k for k in kinds if k not in KINDS})
        if unknown:
            raise ValueError(f"kinds must be one of {KINDS}, got {unknown}")

        if (self.head_position is None) != (self.head_yaw is None):
            raise ValueError("head_position and head_yaw must be given together or not at all")
        head_position = head_yaw = None
        if self.head_position is not None:
            head_position = _float_array("head_position", self.head_position, (n, 2))
            head_yaw = _float_array("head_yaw", self.head_yaw, (n,))
            if np.isinf(head_position).any() or np.isinf(head_yaw).any():
                raise ValueError(
                    "head_position and head_yaw must be finite or NaN (missing), got inf"
                )
            missing_pos = np.isnan(head_position)
            missing_yaw = np.isnan(head_yaw)
            if (missing_pos[:, 0] != missing_pos[:, 1]).any() or (
                missing_pos[:, 0] != missing_yaw
            ).any():
                raise ValueError("a head is either fully observed (x, y, yaw) or fully NaN")
            _check_extent("head_position", head_position, ids)
            _check_yaw("head_yaw", head_yaw)

        groups = None
        if self.groups is not None:
            groups = check_groups(
                (_members(group, f"groups[{g}]") for g, group in enumerate(self.groups)), ids
            )
        listed = None
        if self.listed_groups is not None:
            if groups is None:
                raise ValueError("listed_groups needs groups: the frame is not annotated")
            listed = _validate_listed(self.listed_groups, groups, ids)

        object.__setattr__(self, "ids", _readonly(ids))
        object.__setattr__(self, "position", _readonly(position))
        object.__setattr__(self, "yaw", _readonly(yaw))
        object.__setattr__(self, "kinds", kinds)
        if head_position is not None:
            head_position, head_yaw = _readonly(head_position), _readonly(head_yaw)
        object.__setattr__(self, "head_position", head_position)
        object.__setattr__(self, "head_yaw", head_yaw)
        object.__setattr__(self, "groups", groups)
        object.__setattr__(self, "listed_groups", listed)
        try:
            object.__setattr__(self, "time", float(self.time))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"time must be a number of seconds, got {self.time!r}") from exc
        if not math.isfinite(self.time):
            raise ValueError(f"time must be finite, got {self.time}")
        object.__setattr__(self, "sequence", str(self.sequence))

    @classmethod
    def _trusted_frames(
        cls,
        ids: Iterable[np.ndarray],
        position: Iterable[np.ndarray],
        yaw: Iterable[np.ndarray],
        kinds: Iterable[tuple[str, ...]],
        head_position: Iterable[np.ndarray | None],
        head_yaw: Iterable[np.ndarray | None],
        groups: Iterable[tuple[Group, ...] | None],
        time: Iterable[float],
        sequence: Iterable[str],
    ) -> list[Frame]:
        """Frames from a maker that has checked every value as ``__post_init__`` would, on
        whole columns (the Parquet reader: a file's rows checked at once), made without the
        checks, which would cost a file's reading most of its time. Each argument holds one
        entry a frame, in order.

        The maker guarantees what ``__post_init__`` gives: ``ids`` unique int64, ``position``,
        ``yaw`` and the heads float64 of the shapes documented, C-contiguous, read-only arrays
        nobody else can write to; ``kinds`` tuples of `KINDS`; ``groups`` tuples of tuples of
        Python ints, disjoint, of the frame's ids; ``time`` finite floats; ``sequence`` strs.
        """
        new = object.__new__
        frames = []
        for values in zip(
            ids, position, yaw, kinds, head_position, head_yaw, groups, time, sequence, strict=True
        ):
            frame = new(cls)
            fields = frame.__dict__  # frozen: filled directly, as __post_init__ would set them
            (
                fields["ids"],
                fields["position"],
                fields["yaw"],
                fields["kinds"],
                fields["head_position"],
                fields["head_yaw"],
                fields["groups"],
                fields["time"],
                fields["sequence"],
            ) = values
            fields["listed_groups"] = None
            frames.append(frame)
        return frames

    @property
    def n_people(self) -> int:
        return int(self.ids.size)

    @property
    def annotated(self) -> bool:
        """True when the frame carries ground-truth groups."""
        return self.groups is not None

    @property
    def is_robot(self) -> np.ndarray:
        """(n,) bool: which entries are robots."""
        return np.array([k == ROBOT for k in self.kinds], dtype=bool)

    def partition(self) -> tuple[Group, ...]:
        """The ground truth as a full partition: the groups, then every other person alone.

        Raises:
            ValueError: if the frame is not annotated.
        """
        if self.groups is None:
            raise ValueError("frame is not annotated: it has no ground-truth groups")
        return complete_partition(self.groups, self.ids)

    def fformations(self) -> tuple[Group, ...]:
        """The ground-truth F-formations: groups of two or more people."""
        if self.groups is None:
            raise ValueError("frame is not annotated: it has no ground-truth groups")
        return tuple(g for g in self.groups if len(g) >= 2)

    def truth_fformations(self) -> tuple[Group, ...]:
        """The F-formations the evaluation scores against: ``listed_groups`` when the annotation
        names people absent from the frame, else :meth:`fformations`."""
        if self.listed_groups is not None:
            return self.listed_groups
        return self.fformations()

    @property
    def unseen_members(self) -> tuple[int, ...]:
        """Ids the ground truth names that are not among the frame's people (sorted)."""
        if self.listed_groups is None:
            return ()
        present = set(self.ids.tolist())
        return tuple(sorted({m for g in self.listed_groups for m in g} - present))

    def index_of(self, person_id: int) -> int:
        """Row of ``person_id`` in this frame's arrays."""
        hits = np.flatnonzero(self.ids == person_id)
        if hits.size == 0:
            raise KeyError(f"person {person_id} is not in this frame (ids {self.ids.tolist()})")
        return int(hits[0])

    def replace(self, **changes: Any) -> Frame:
        """A copy with some fields changed (validated again)."""
        fields = {
            "ids": self.ids,
            "position": self.position,
            "yaw": self.yaw,
            "kinds": self.kinds,
            "head_position": self.head_position,
            "head_yaw": self.head_yaw,
            "groups": self.groups,
            "time": self.time,
            "sequence": self.sequence,
            "listed_groups": self.listed_groups,
        }
        fields.update(changes)
        return Frame(**fields)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Frame):
            return NotImplemented
        return (
            np.array_equal(self.ids, other.ids)
            and np.array_equal(self.position, other.position)
            and np.array_equal(self.yaw, other.yaw)
            and self.kinds == other.kinds
            and _optional_equal(self.head_position, other.head_position)
            and _optional_equal(self.head_yaw, other.head_yaw)
            and self.groups == other.groups
            and self.time == other.time
            and self.sequence == other.sequence
            and self.listed_groups == other.listed_groups
        )

    __hash__ = None  # type: ignore[assignment]


def _optional_equal(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return np.array_equal(a, b, equal_nan=True)


def _members(group: Any, name: str) -> Group:
    """``group`` as a tuple of person ids; errors name it ``name`` (``groups[2]``)."""
    if isinstance(group, (str, bytes)) or not isinstance(group, Iterable):
        raise ValueError(f"{name} must be a sequence of person ids, got {group!r}")
    return tuple(_person_id(m, name) for m in group)


def check_groups(
    groups: Iterable[Group],
    ids: npt.ArrayLike,
    *,
    at: str = "",
    noun: str = "person",
    place: str = "frame",
) -> tuple[Group, ...]:
    """``groups`` as a tuple, checked to be non-empty, disjoint groups of ids among ``ids``.

    The ids named in no group stand alone: the groups need not cover ``ids``.

    Args:
        groups: the groups, each a tuple of int ids.
        ids: the ids there are.
        at: when or where the groups hold, after their name in messages (``" at t=2 s"``).
        noun: what an id stands for in messages (``"agent"``).
        place: what holds the ids, in messages (``"scene"``).

    Raises:
        ValueError: naming the first fault, e.g. ``"groups[1] is empty"``, ``"groups[0] names
            person 7, who is not in the frame (ids [1, 2, 3])"`` or ``"groups must be disjoint,
            person 1 appears twice (groups[1])"``.
    """
    known = set(np.asarray(ids).tolist())
    seen: set[int] = set()
    out = []
    for g, members in enumerate(groups):
        if not members:
            raise ValueError(f"groups[{g}]{at} is empty")
        for m in members:
            if m not in known:
                raise ValueError(
                    f"groups[{g}]{at} names {noun} {m}, who is not in the {place} "
                    f"(ids {sorted(known)})"
                )
            if m in seen:
                raise ValueError(
                    f"groups{at} must be disjoint, {noun} {m} appears twice (groups[{g}])"
                )
            seen.add(m)
        out.append(members)
    return tuple(out)


def _validate_listed(
    listed: Iterable[Iterable[int]], groups: tuple[Group, ...], ids: np.ndarray
) -> tuple[Group, ...]:
    """``listed_groups`` checked: disjoint groups of two or more whose present members are
    ``groups``' F-formations."""
    present = set(ids.tolist())
    seen: set[int] = set()
    out = []
    for g, group in enumerate(listed):
        members = _members(group, f"listed_groups[{g}]")
        if len(members) < 2:
            raise ValueError(f"listed_groups[{g}] must have two or more members, got {members}")
        for m in members:
            if m in seen:
                raise ValueError(
                    f"listed_groups must be disjoint, person {m} appears twice (listed_groups[{g}])"
                )
            seen.add(m)
        out.append(members)
    observed = sorted(
        sorted(kept) for kept in ([m for m in g if m in present] for g in out) if len(kept) >= 2
    )
    fformations = sorted(sorted(g) for g in groups if len(g) >= 2)
    if observed != fformations:
        raise ValueError(
            "listed_groups' members present in the frame must be groups' F-formations: "
            f"expected {fformations}, got {observed}"
        )
    return tuple(out)


def _person_id(value: Any, where: str) -> int:
    """``value`` as an int id; integral floats are accepted, anything else is an error."""
    if not isinstance(value, (bool, np.bool_)):
        try:
            return operator.index(value)
        except TypeError:
            if isinstance(value, (float, np.floating)) and float(value).is_integer():
                return int(value)
    raise ValueError(f"{where} must hold integer person ids, got {value!r}")


def check_frames(frames: Iterable[Any], *, caller: str | None = None) -> tuple[Frame, ...]:
    """The entries of ``frames`` as a tuple, each checked to be a :class:`Frame`.

    Args:
        frames: the entries (a Dataset works too).
        caller: the checking function's name, for the message ``"<caller> takes reform.Frame
            objects, got <type> at frames[k]"``; without it the message is ``"frames[k] must be a
            reform.Frame, got <type>"``.

    Raises:
        TypeError: at the first entry that is not a Frame.
    """
    frames = tuple(frames)
    for k, frame in enumerate(frames):
        if not isinstance(frame, Frame):
            found = type(frame).__name__
            if caller is None:
                raise TypeError(f"frames[{k}] must be a reform.Frame, got {found}")
            raise TypeError(f"{caller} takes reform.Frame objects, got {found} at frames[{k}]")
    return frames


def _check_time_order(frames: Sequence[Frame]) -> None:
    """Raises unless every sequence's times increase strictly in the order given."""
    last: dict[str, tuple[int, float]] = {}
    for k, frame in enumerate(frames):
        previous = last.get(frame.sequence)
        if previous is not None and not frame.time > previous[1]:
            raise ValueError(
                f"frames[{k}].time must increase within sequence {frame.sequence!r}: expected "
                f"> {previous[1]!r} (frames[{previous[0]}]), got {frame.time!r}; give each "
                "Frame its time= (and frames of different recordings their own sequence=)"
            )
        last[frame.sequence] = (k, frame.time)


def complete_partition(groups: Iterable[Sequence[int]], ids: Iterable[int]) -> tuple[Group, ...]:
    """``groups`` plus a singleton for every id in no group (in ``ids`` order)."""
    groups = tuple(tuple(int(m) for m in g) for g in groups)
    grouped = {m for g in groups for m in g}
    return groups + tuple((int(i),) for i in ids if int(i) not in grouped)


@dataclass(frozen=True, eq=False)
class Dataset:
    """An ordered sequence of frames with its provenance.

    Within each sequence the frames' times increase strictly, in the order the frames are
    given (frames of different sequences may interleave).

    Attributes:
        frames: the frames, in recording order (sequence by sequence, time increasing).
        name: short name, e.g. ``"salsa"``.
        source: where the data came from (a path or a generator description).
        units: length unit of every position, always ``"m"`` once loaded.
        metadata: free-form provenance (generator version, seed, parameters, loader report).
    """

    frames: tuple[Frame, ...]
    name: str
    source: str = ""
    units: str = "m"
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        frames = check_frames(self.frames)
        if self.units != "m":
            raise ValueError(f"units must be 'm' (loaders convert to metres), got {self.units!r}")
        _check_time_order(frames)
        object.__setattr__(self, "frames", frames)
        object.__setattr__(self, "metadata", MappingProxyType(dict(self.metadata)))

    def __len__(self) -> int:
        return len(self.frames)

    def __iter__(self) -> Iterator[Frame]:
        return iter(self.frames)

    def __getitem__(self, index: int) -> Frame:
        return self.frames[index]

    def annotated(self) -> tuple[Frame, ...]:
        """The frames that carry ground truth."""
        return tuple(f for f in self.frames if f.groups is not None)

    def sequences(self) -> tuple[str, ...]:
        """Names of the sequences, in order of first appearance."""
        return tuple(dict.fromkeys(f.sequence for f in self.frames))

    def subset(self, frames: Iterable[Frame], *, name: str | None = None) -> Dataset:
        """A dataset with the same provenance holding ``frames``."""
        return Dataset(
            frames=tuple(frames),
            name=self.name if name is None else name,
            source=self.source,
            units=self.units,
            metadata=self.metadata,
        )

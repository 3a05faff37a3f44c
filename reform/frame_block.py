"""Frames as columns: consecutive instants of one sequence over a fixed roster (`FrameBlock`).

A `Frame` holds one instant of the people present then; a `FrameBlock` holds ``T`` instants of
a roster of ``n`` agents as arrays, with ``present`` saying who was in the scene at each
instant. It is the same data as the frames ``block.frames()`` gives, without making a Python
object per instant: the simulator's fast path yields blocks (`sim.world.World.rollout`), the
Parquet writer writes them (`reform.datasets.write_parquet`), a recording reads them, and
whoever wants frames takes them from the block.

The groups are the ones declared at each instant, which may name agents absent then (a script
says who belongs together; someone may not have walked in yet). `FrameBlock.present_groups` is
the one place that restricts them to the people present (`reform.perturb.restrict_groups`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from reform.frame import KINDS, POSITION_LIMIT_M, Frame, Group, check_groups
from reform.perturb import restrict_groups

__all__ = ["FrameBlock"]

_YAW_LIMIT_RAD = math.pi + 2e-3  # wrapped radians plus rounding, as `Frame` accepts them


@dataclass(frozen=True, eq=False)
class FrameBlock:
    """Poses of every agent of a roster at consecutive times of one sequence.

    Poses of agents absent at an instant are ignored (the simulator leaves them where they were
    parked). Arrays are read-only; values are checked as `Frame` checks them, on whole arrays.

    Attributes:
        time: (T,) seconds.
        ids: (n,) int64 agent ids, unique.
        kinds: n strings, ``"human"`` or ``"robot"``.
        present: (T, n) bool, who is in the scene at each instant.
        position: (T, n, 2) body position on the ground plane, metres (finite where present).
        yaw: (T, n) body yaw, radians in [-pi, pi] (where present).
        head_position: (T, n, 2) head position, metres (NaN: head not observed), or None when
            the source has no heads.
        head_yaw: (T, n) head yaw, radians, NaN exactly where ``head_position`` is; None with it.
        groups: T entries: the groups declared at each instant (non-empty tuples of roster ids,
            disjoint), or ``None`` where the instant is not annotated.
        sequence: the name of the sequence.
    """

    time: np.ndarray
    ids: np.ndarray
    kinds: tuple[str, ...]
    present: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_position: np.ndarray | None
    head_yaw: np.ndarray | None
    groups: tuple[tuple[Group, ...] | None, ...]
    sequence: str = ""

    def __post_init__(self) -> None:
        time = _frozen(self.time, np.float64)
        ids = np.asarray(self.ids)
        if ids.ndim != 1 or (ids.size and not np.issubdtype(ids.dtype, np.integer)):
            raise ValueError(f"ids must be integers with shape (n,), got {ids.dtype} {ids.shape}")
        ids = _frozen(ids, np.int64)
        if time.ndim != 1:
            raise ValueError(f"time must have shape (T,), got {time.shape}")
        t, n = time.size, ids.size
        if np.unique(ids).size != n:
            raise ValueError(f"ids must be unique, got {ids.tolist()}")
        kinds = tuple(self.kinds)
        if len(kinds) != n or any(k not in KINDS for k in kinds):
            raise ValueError(f"kinds must be {n} entries among {KINDS}, got {kinds}")
        if len(self.groups) != t:
            raise ValueError(f"groups must have {t} entries, got {len(self.groups)}")
        arrays = {"present": bool, "position": np.float64, "yaw": np.float64}
        if (self.head_position is None) != (self.head_yaw is None):
            raise ValueError("head_position and head_yaw must be given together or not at all")
        if self.head_position is not None:
            arrays |= {"head_position": np.float64, "head_yaw": np.float64}
        shapes = {
            "present": (t, n),
            "position": (t, n, 2),
            "yaw": (t, n),
            "head_position": (t, n, 2),
            "head_yaw": (t, n),
        }
        values = {name: _frozen(getattr(self, name), dtype) for name, dtype in arrays.items()}
        for name, array in values.items():
            if array.shape != shapes[name]:
                raise ValueError(f"{name} must have shape {shapes[name]}, got {array.shape}")
        for name, value in (("time", time), ("ids", ids), ("kinds", kinds), *values.items()):
            object.__setattr__(self, name, value)
        if not isinstance(self.sequence, str):
            raise ValueError(f"sequence must be a string, got {self.sequence!r}")
        object.__setattr__(self, "groups", tuple(self.groups))
        self._check_values()
        self._check_groups()

    @classmethod
    def _trusted(cls, **fields: Any) -> FrameBlock:
        """A block from a maker that guarantees every value (the world's rollout: poses it
        computed itself, a roster and groups it checked when the scene and the script were
        made), its arrays its own to freeze: made without the checks, which would cost the
        simulator's fast path a tenth of its time."""
        block = object.__new__(cls)
        for name, value in fields.items():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            object.__setattr__(block, name, value)
        return block

    def _check_groups(self) -> None:
        before: Any = None
        for t, declared in enumerate(self.groups):
            if declared is None or declared is before or declared == before:
                continue
            before = declared
            check_groups(declared, self.ids, at=f" at row {t}", place="roster")

    def _check_values(self) -> None:
        present = self.present
        position, yaw = self.position[present], self.yaw[present]
        if not np.all(np.isfinite(self.time)):
            raise ValueError("time must be finite, got NaN or inf")
        if np.any(np.diff(self.time) <= 0.0):
            k = int(np.flatnonzero(np.diff(self.time) <= 0.0)[0])
            raise ValueError(
                f"time must increase, got {self.time[k]:g} s then {self.time[k + 1]:g} s at rows "
                f"{k} and {k + 1}"
            )
        if not (np.all(np.isfinite(position)) and np.all(np.isfinite(yaw))):
            raise ValueError("position and yaw must be finite where present, got NaN or inf")
        if np.any(np.abs(position) > POSITION_LIMIT_M):
            raise ValueError(
                f"position must be metres with |x|, |y| <= {POSITION_LIMIT_M:g} where present, "
                f"got {float(np.max(np.abs(position))):g}"
            )
        if np.any(np.abs(yaw) > _YAW_LIMIT_RAD):
            raise ValueError(
                "yaw must be radians wrapped to [-pi, pi] (wrap with reform.wrap_angle)"
            )
        if self.head_position is None:
            return
        hp, hy = self.head_position[present], self.head_yaw[present]
        missing = np.isnan(hp)
        if (
            np.any(np.isinf(hp))
            or np.any(np.isinf(hy))
            or np.any(missing[:, 0] != missing[:, 1])
            or np.any(missing[:, 0] != np.isnan(hy))
        ):
            raise ValueError("a head is either fully observed (x, y, yaw) or fully NaN, never inf")
        if np.any(np.abs(hy[~np.isnan(hy)]) > _YAW_LIMIT_RAD):
            raise ValueError("head_yaw must be radians wrapped to [-pi, pi]")
        if np.any(np.abs(hp[~np.isnan(hp)]) > POSITION_LIMIT_M):
            raise ValueError(
                f"head_position must be metres with |x|, |y| <= {POSITION_LIMIT_M:g} where present"
            )

    def __len__(self) -> int:
        return int(self.time.shape[0])

    @classmethod
    def concatenate(cls, blocks: Sequence[FrameBlock]) -> FrameBlock:
        """The instants of ``blocks`` one after the other: one roster, one sequence, heads in
        all or none."""
        blocks = list(blocks)
        if not blocks:
            raise ValueError("concatenate needs at least one block, got none")
        first = blocks[0]
        for k, block in enumerate(blocks[1:], start=1):
            if (
                not np.array_equal(block.ids, first.ids)
                or block.kinds != first.kinds
                or block.sequence != first.sequence
                or (block.head_position is None) != (first.head_position is None)
            ):
                raise ValueError(
                    f"block {k} differs from block 0 in its roster, sequence or heads: ids "
                    f"{block.ids.tolist()}, sequence {block.sequence!r}, heads "
                    f"{block.head_position is not None} against {first.ids.tolist()}, "
                    f"{first.sequence!r}, {first.head_position is not None}"
                )
        for k in range(1, len(blocks)):
            before, after = blocks[k - 1], blocks[k]
            if len(before) and len(after) and after.time[0] <= before.time[-1]:
                raise ValueError(
                    f"block {k} must start after block {k - 1} ends, got {after.time[0]:g} s "
                    f"after {before.time[-1]:g} s"
                )
        heads = first.head_position is not None

        def joined(name: str) -> np.ndarray | None:
            if name.startswith("head") and not heads:
                return None
            return np.concatenate([getattr(b, name) for b in blocks])

        # Each block was checked when it was made (or made by the simulator): joined in time
        # order over one roster, they need no second look.
        return cls._trusted(
            time=joined("time"),
            ids=first.ids,
            kinds=first.kinds,
            present=joined("present"),
            position=joined("position"),
            yaw=joined("yaw"),
            head_position=joined("head_position"),
            head_yaw=joined("head_yaw"),
            groups=tuple(g for b in blocks for g in b.groups),
            sequence=first.sequence,
        )

    def present_groups(self) -> tuple[tuple[Group, ...] | None, ...]:
        """Each instant's groups restricted to the agents present then (``None`` where not
        annotated): a group of which one member is present becomes that member, one left empty
        is dropped (`reform.perturb.restrict_groups`). Worked out again only where the declared
        groups or the people present change, and once per block (a block does not change): the
        writer and the summaries of a generated shard ask for them each."""
        known = self.__dict__.get("_present_groups")
        if known is not None:
            return known
        changed = np.ones(len(self), dtype=bool)
        changed[1:] = np.any(self.present[1:] != self.present[:-1], axis=1)
        out: list[tuple[Group, ...] | None] = []
        before: Any = None
        restricted: tuple[Group, ...] | None = None
        for row, declared in enumerate(self.groups):
            if declared is None:
                restricted = None
            elif changed[row] or before is None or not (declared is before or declared == before):
                restricted = restrict_groups(declared, set(self.ids[self.present[row]].tolist()))
            before = declared
            out.append(restricted)
        groups = tuple(out)
        object.__setattr__(self, "_present_groups", groups)
        return groups

    def frame(self, row: int) -> Frame:
        """Instant ``row`` as a Frame of the agents present then, its groups restricted to them."""
        declared = self.groups[row]
        ids = set(self.ids[self.present[row]].tolist())
        return self._frame(row, None if declared is None else restrict_groups(declared, ids))

    def frames(self) -> Iterator[Frame]:
        """Every instant as a Frame."""
        for row, groups in enumerate(self.present_groups()):
            yield self._frame(row, groups)

    def _frame(self, row: int, groups: tuple[Group, ...] | None) -> Frame:
        keep = self.present[row]
        heads = self.head_position is not None
        return Frame(
            ids=self.ids[keep],
            kinds=tuple(k for k, p in zip(self.kinds, keep, strict=True) if p),
            position=self.position[row, keep],
            yaw=self.yaw[row, keep],
            head_position=self.head_position[row, keep] if heads else None,
            head_yaw=self.head_yaw[row, keep] if heads else None,
            groups=groups,
            time=float(self.time[row]),
            sequence=self.sequence,
        )


def _frozen(values: Any, dtype: Any) -> np.ndarray:
    """A read-only array of ``values`` as ``dtype`` (a copy when the caller's array would
    otherwise be frozen or converted)."""
    array = np.array(values, dtype=dtype, copy=True)
    array.flags.writeable = False
    return array

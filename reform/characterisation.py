"""Shape of an F-formation: how tight its members stand and how evenly they spread around it.

The paper's "Characterisation" section compares group sizes by two numbers:

* **Tightness**: the mean Euclidean distance of the members to the group's centre, the mean of
  their positions (metres).
* **Symmetry**: order the N members by angle around the centre; ``theta_ij`` is the angle
  (degrees) between adjacent members, N gaps closing the circle; ``theta_perfect = 360/N``;
  ``S = sum |theta_perfect - theta_ij|``. 0 is perfectly symmetric; defined as 0 for N = 2.

:func:`characterise` applies both to every F-formation (two or more people) of the annotated
frames of a dataset, vectorised over the groups of each size (:func:`batch_tightness`,
:func:`batch_symmetry`).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from reform.frame import Frame

__all__ = [
    "GroupShapes",
    "batch_symmetry",
    "batch_tightness",
    "characterise",
    "symmetry",
    "tightness",
]

FULL_TURN_DEG = 360.0  # degrees


def _member_positions(positions: npt.ArrayLike, *, batch: bool = False) -> np.ndarray:
    """Checked float64 positions of one group's members, or (``batch``) of many groups'."""
    array = np.asarray(positions, dtype=np.float64)
    ndim, shape, per_group = (
        (3, "(n_groups, n_members, 2)", " per group") if batch else (2, "(n_members, 2)", "")
    )
    if array.ndim != ndim or array.shape[-1] != 2:
        raise ValueError(f"positions must have shape {shape}, got {array.shape}")
    if array.shape[-2] < 2:
        raise ValueError(
            f"positions must hold at least 2 members{per_group} (an F-formation), "
            f"got {array.shape[-2]}"
        )
    if not np.all(np.isfinite(array)):
        raise ValueError("positions must be finite, got NaN or inf")
    return array


def tightness(positions: npt.ArrayLike) -> float:
    """Mean distance of the members to the group's centre (the mean of their positions).

    Args:
        positions: (n_members, 2) ground-plane positions, metres; n_members >= 2.

    Returns:
        Tightness in metres.

    Raises:
        ValueError: if ``positions`` is not (n >= 2, 2) or not finite.
    """
    members = _member_positions(positions)
    centre = members.mean(axis=0)
    return float(np.linalg.norm(members - centre, axis=1).mean())


def symmetry(positions: npt.ArrayLike) -> float:
    """Sum of the deviations of the angular gaps between adjacent members from 360/N.

    Args:
        positions: (n_members, 2) ground-plane positions, metres; n_members >= 2.

    Returns:
        Symmetry in degrees, >= 0; 0 for a perfectly even spread and, by definition, for pairs.

    Raises:
        ValueError: if ``positions`` is not (n >= 2, 2) or not finite.
    """
    members = _member_positions(positions)
    n = members.shape[0]
    if n == 2:
        return 0.0
    offsets = members - members.mean(axis=0)
    angles = np.sort(np.degrees(np.arctan2(offsets[:, 1], offsets[:, 0])))
    gaps = np.diff(angles, append=angles[0] + FULL_TURN_DEG)
    return float(np.abs(FULL_TURN_DEG / n - gaps).sum())


@dataclass(frozen=True, eq=False)
class GroupShapes:
    """Tightness and Symmetry of every F-formation of a set of frames.

    Attributes:
        size: (n_groups,) int64 number of members.
        tightness: (n_groups,) float64 metres.
        symmetry: (n_groups,) float64 degrees.
    """

    size: np.ndarray
    tightness: np.ndarray
    symmetry: np.ndarray

    def __post_init__(self) -> None:
        size = np.asarray(self.size, dtype=np.int64)
        n = size.shape[0] if size.ndim == 1 else -1
        for name, value in (("tightness", self.tightness), ("symmetry", self.symmetry)):
            if np.shape(value) != (n,):
                raise ValueError(f"{name} must have shape ({n},) like size, got {np.shape(value)}")
        for name, value in (
            ("size", size),
            ("tightness", np.asarray(self.tightness, dtype=np.float64)),
            ("symmetry", np.asarray(self.symmetry, dtype=np.float64)),
        ):
            value = np.array(value, copy=True)
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    def sizes(self) -> tuple[int, ...]:
        """The group sizes present, increasing."""
        return tuple(int(s) for s in np.unique(self.size))

    def mean_by_size(self) -> dict[int, tuple[float, float, int]]:
        """``size -> (mean tightness m, mean symmetry deg, number of groups)``."""
        return {
            s: (
                float(self.tightness[self.size == s].mean()),
                float(self.symmetry[self.size == s].mean()),
                int(np.count_nonzero(self.size == s)),
            )
            for s in self.sizes()
        }


def batch_tightness(positions: npt.ArrayLike) -> np.ndarray:
    """:func:`tightness` of many groups of the same size at once.

    Args:
        positions: (n_groups, n_members, 2) ground-plane positions, metres; n_members >= 2.

    Returns:
        (n_groups,) float64 Tightness, metres.
    """
    members = _member_positions(positions, batch=True)
    offsets = members - members.mean(axis=1, keepdims=True)
    return np.sqrt((offsets * offsets).sum(axis=2)).mean(axis=1)


def batch_symmetry(positions: npt.ArrayLike) -> np.ndarray:
    """:func:`symmetry` of many groups of the same size at once.

    Args:
        positions: (n_groups, n_members, 2) ground-plane positions, metres; n_members >= 2.

    Returns:
        (n_groups,) float64 Symmetry, degrees; zeros for pairs.
    """
    members = _member_positions(positions, batch=True)
    n_groups, n = members.shape[:2]
    if n == 2:
        return np.zeros(n_groups, dtype=np.float64)
    offsets = members - members.mean(axis=1, keepdims=True)
    angles = np.sort(np.degrees(np.arctan2(offsets[..., 1], offsets[..., 0])), axis=1)
    gaps = np.diff(angles, axis=1, append=angles[:, :1] + FULL_TURN_DEG)
    return np.abs(FULL_TURN_DEG / n - gaps).sum(axis=1)


def characterise(frames: Iterable[Frame]) -> GroupShapes:
    """Tightness and Symmetry of every ground-truth F-formation of the annotated frames.

    Args:
        frames: frames in any order; frames without ground truth are skipped.

    Returns:
        One entry per F-formation (group of two or more), frame by frame, in each frame's
        group order.
    """
    sizes: list[int] = []
    # size -> (entry numbers, member positions (n, 2) of each entry)
    by_size: dict[int, tuple[list[int], list[np.ndarray]]] = {}
    for frame in frames:
        if frame.groups is None:
            continue
        row_of = {person: row for row, person in enumerate(frame.ids.tolist())}
        for group in frame.groups:
            n = len(group)
            if n < 2:
                continue
            entries, members = by_size.setdefault(n, ([], []))
            entries.append(len(sizes))
            members.append(frame.position[[row_of[person] for person in group]])
            sizes.append(n)
    tight = np.empty(len(sizes), dtype=np.float64)
    sym = np.empty(len(sizes), dtype=np.float64)
    for entries, members in by_size.values():
        stacked = np.stack(members)
        tight[entries] = batch_tightness(stacked)
        sym[entries] = batch_symmetry(stacked)
    return GroupShapes(size=np.asarray(sizes, dtype=np.int64), tightness=tight, symmetry=sym)

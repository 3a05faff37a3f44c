"""Deconstruction: a frame of n people becomes n(n-1)/2 unordered pairs, each with features.

The paper's two features (see the project's reference definitions):

* **Distance** ``d_ij = ||p_i - p_j||`` in metres, on the ground plane.
* **Effort Angle** ``EA_ij = a_i + a_j`` in radians, ``[0, 2*pi]``, where
  ``phi_ij = atan2(y_j - y_i, x_j - x_i)``, ``a_i = |wrap(phi_ij - theta_i)|`` and
  ``a_j = |wrap(phi_ji - theta_j)|``: how far both would have to turn to face each other.
  0 means face to face, ``2*pi`` back to back, and ``EA_ij = EA_ji``.

Optional extras, off by default: the same two computed from the head (falling back to the body
for a person whose head was not observed) and a flag for pairs that involve a robot.

**Scale-free features** (the ``"relative"`` set, :data:`FEATURE_SETS`: relative distance and
o-space distance), for a classifier trained
on one kind of data (simulated crowds, one dataset) that must work on datasets measured at other
scales: group radii differ about twofold between the field's datasets, and positions estimated
from video carry a per-dataset scale error. Distances are divided by the **frame's scale**
:func:`frame_scale`, measured from the frame itself: the median, over the frame's people, of the
distance to their nearest neighbour. Most people of a social scene stand in a group and their
nearest neighbour is a group mate, so the median nearest-neighbour distance is the frame's
conversational distance, and it scales with the positions: multiplying every position of a frame
by any factor leaves these features unchanged. (The median, not the mean, so that a few people
standing alone do not move it; the statistic is a fixed definition, not fitted on any data.)

* **Relative distance** ``d_ij / s``, dimensionless.
* **O-space distance** ``||o_i - o_j|| / s`` with ``o_i = p_i + (s / 2) u_i``, ``u_i`` the unit
  vector of ``theta_i``: how far apart the two people's o-space centres are, each placed half
  the frame's scale in front of its person (two people face to face at distance ``s`` share one
  centre, the midpoint, and score 0). It joins distance and orientation in one number, as GCFF's
  votes do, without GCFF's stride in metres.
* **Larger turn** ``max(a_i, a_j)`` in radians, ``[0, pi]``: the turn of the member who faces
  the other least. With the Effort Angle (their sum) it separates "both half-turned" from "one
  faces the other, who looks away". Angles of the line between two people survive coarse
  orientation coding (4 or 8 directions) as well as the Effort Angle does.

What chose the set (SALSA's training split only, time-blocked cross-validation, Bagged Trees,
``sim.experiments.reform_options`` and ``docs/guide/reform-options.md``): relative distance with
the o-space distance scores as relative distance + Effort Angle + o-space distance (pair
accuracy 0.927 against 0.928; with orientations coded in 8 or 4 directions 0.921 against 0.922
and 0.907 against 0.908) and better than relative distance + Effort Angle (0.919); the Larger
Turn added nothing. Of the two, the set of two features is kept: a tree ensemble on two features
compiles into one exact lookup table (:mod:`reform.fast`), ten times faster than evaluating its
trees on three.

The frame's scale of a frame of 2 people is their distance (each is the other's nearest
neighbour), so their relative distance is 1 and only the orientations and the o-space distance
tell them apart; a frame of 0 or 1 person has no pairs. People at one spot (a nearest
neighbour at distance 0) are left out of the median; a frame in which everyone shares a spot
with someone has scale 1 (its distances are all 0 anyway).

Pairs are always listed in the order of :func:`pair_indices`: ``(0, 1), (0, 2), ..., (n-2, n-1)``
over the rows of the frame's arrays. Every function here is vectorised over pairs and, for the
batch functions, over frames too.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Mapping, Sequence
from types import MappingProxyType

import numpy as np
import numpy.typing as npt

from reform.frame import Frame

DISTANCE = "distance"  # metres
EFFORT_ANGLE = "effort_angle"  # radians, [0, 2*pi]
HEAD_DISTANCE = "head_distance"  # metres, head positions (body where the head is unknown)
HEAD_EFFORT_ANGLE = "head_effort_angle"  # radians, head yaws (body where the head is unknown)
INVOLVES_ROBOT = "involves_robot"  # 1.0 when either member of the pair is a robot, else 0.0
RELATIVE_DISTANCE = "relative_distance"  # Distance / frame_scale, dimensionless
OSPACE_DISTANCE = "ospace_distance"  # o-space centres' distance / frame_scale, dimensionless
LARGER_TURN = "larger_turn"  # radians, [0, pi]: max(a_i, a_j)

FEATURES = (
    DISTANCE,
    EFFORT_ANGLE,
    HEAD_DISTANCE,
    HEAD_EFFORT_ANGLE,
    INVOLVES_ROBOT,
    RELATIVE_DISTANCE,
    OSPACE_DISTANCE,
    LARGER_TURN,
)
DEFAULT_FEATURES = (DISTANCE, EFFORT_ANGLE)
PAPER = "paper"
RELATIVE = "relative"
# Named feature sets, accepted wherever a feature list is (``Reform(features="relative")``).
FEATURE_SETS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        PAPER: DEFAULT_FEATURES,
        RELATIVE: (RELATIVE_DISTANCE, OSPACE_DISTANCE),
    }
)
OSPACE_STRIDE = 0.5  # o-space centre in front of each person, in units of the frame's scale
_SCALE_MATRIX_PEOPLE = 512  # up to this many people: nearest neighbours from the pair distances
MAX_PAIRS = 2**30  # pairs of one frame (46,341 people): pair_indices refuses more before any
# array is made, as their two index arrays alone would take 16 GiB

__all__ = [
    "DEFAULT_FEATURES",
    "DISTANCE",
    "EFFORT_ANGLE",
    "FEATURES",
    "FEATURE_SETS",
    "HEAD_DISTANCE",
    "HEAD_EFFORT_ANGLE",
    "INVOLVES_ROBOT",
    "LARGER_TURN",
    "MAX_PAIRS",
    "OSPACE_DISTANCE",
    "OSPACE_STRIDE",
    "PAPER",
    "RELATIVE",
    "RELATIVE_DISTANCE",
    "batch_pair_features",
    "check_features",
    "effort_angle",
    "frame_scale",
    "frame_pair_features",
    "pair_indices",
]


def check_features(features: str | Sequence[str]) -> tuple[str, ...]:
    """Validates a feature list: known names, no repeats, at least one; or a feature set's name.

    Args:
        features: names from :data:`FEATURES`, or one name of :data:`FEATURE_SETS`
            (``"paper"``, ``"relative"``).

    Returns:
        The features as a tuple (a set's name resolved to its features).

    Raises:
        ValueError: naming the unknown or repeated feature.
    """
    if isinstance(features, str):
        if features in FEATURE_SETS:
            return FEATURE_SETS[features]
        raise ValueError(
            f"features must be a feature set ({', '.join(map(repr, FEATURE_SETS))}) or a "
            f"sequence of feature names from {FEATURES}, got the string {features!r}"
        )
    features = tuple(features)
    if not features:
        raise ValueError(f"features must name at least one of {FEATURES}, got ()")
    for name in features:
        if name not in FEATURES:
            raise ValueError(f"features must be among {FEATURES}, got {name!r}")
    repeated = sorted({name for name in features if features.count(name) > 1})
    if repeated:
        raise ValueError(f"features must not repeat, got {repeated} more than once")
    return features


@functools.lru_cache(maxsize=256)
def _pair_indices(n: int) -> tuple[np.ndarray, np.ndarray]:
    i, j = np.triu_indices(n, k=1)
    i = i.astype(np.intp)
    j = j.astype(np.intp)
    i.flags.writeable = False
    j.flags.writeable = False
    return i, j


def pair_indices(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Row indices ``(i, j)``, ``i < j``, of the n(n-1)/2 pairs of n people, in row-major order.

    Args:
        n: number of people, >= 0.

    Returns:
        Two read-only (n(n-1)/2,) intp arrays.

    Raises:
        ValueError: ``n < 0``, or more than :data:`MAX_PAIRS` pairs (before any allocation).
    """
    n = int(n)
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    pairs = n * (n - 1) // 2
    if pairs > MAX_PAIRS:
        raise ValueError(
            f"a frame of {n:,} people has {pairs:,} pairs, more than reform.features.MAX_PAIRS "
            f"= {MAX_PAIRS:,}: their indices alone would take {pairs * 16 / 2**30:,.0f} GiB"
        )
    return _pair_indices(n)


def _fold(delta: np.ndarray) -> np.ndarray:
    """In place: ``delta`` -> ``|wrap(delta)|`` in ``[0, pi]``, for ``|delta| <= 2*pi`` (+ tol).

    ``pi - |pi - |delta||`` folds ``[0, 2*pi]`` onto ``[0, pi]`` without a modulo; the outer
    ``abs`` handles the few thousandths of a radian beyond ``2*pi`` that wrapped yaws allow.
    """
    np.abs(delta, out=delta)
    np.subtract(np.pi, delta, out=delta)
    np.abs(delta, out=delta)
    np.subtract(np.pi, delta, out=delta)
    return np.abs(delta, out=delta)


def effort_angle(
    position_i: npt.ArrayLike,
    yaw_i: npt.ArrayLike,
    position_j: npt.ArrayLike,
    yaw_j: npt.ArrayLike,
) -> np.ndarray:
    """Effort Angle of pairs: how much both must turn to face each other directly.

    Args:
        position_i: (..., 2) positions of the first members, metres.
        yaw_i: (...) their yaws, radians in ``[-pi, pi]``.
        position_j: (..., 2) positions of the second members, metres.
        yaw_j: (...) their yaws, radians in ``[-pi, pi]``.

    Returns:
        (...) float64 Effort Angles in ``[0, 2*pi]`` radians. Two people at the same spot have
        no direction between them; their ``phi`` is taken as 0 (``atan2(0, 0)``).
    """
    position_i = np.asarray(position_i, dtype=np.float64)
    position_j = np.asarray(position_j, dtype=np.float64)
    delta = position_j - position_i
    phi = np.atleast_1d(np.arctan2(delta[..., 1], delta[..., 0]))
    shape = np.broadcast_shapes(delta.shape[:-1], np.shape(yaw_i), np.shape(yaw_j))
    yaw_i = np.atleast_1d(np.asarray(yaw_i, dtype=np.float64))
    yaw_j = np.atleast_1d(np.asarray(yaw_j, dtype=np.float64))
    return _effort_from_phi(phi, yaw_i, yaw_j).reshape(shape)


def _effort_from_phi(phi: np.ndarray, yaw_i: np.ndarray, yaw_j: np.ndarray) -> np.ndarray:
    # a_i = |wrap(phi_ij - theta_i)|; as phi_ji = phi_ij + pi and |wrap(x + pi)| = pi - |wrap(x)|,
    # a_j = pi - |wrap(phi_ij - theta_j)|. Both differences lie within 2*pi (plus tolerance) of 0.
    a_i = _fold(np.subtract(phi, yaw_i))
    a_j = _fold(np.subtract(phi, yaw_j))
    np.subtract(np.pi, a_j, out=a_j)
    return np.add(a_i, a_j, out=a_i)


def _distance_and_effort(
    position: np.ndarray, yaw: np.ndarray, i: np.ndarray, j: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Distance and Effort Angle of the pairs ``(i, j)`` of (F, n, 2) positions, (F, n) yaws."""
    x = position[..., 0]
    y = position[..., 1]
    dx = np.take(x, j, axis=-1)
    dx -= np.take(x, i, axis=-1)
    dy = np.take(y, j, axis=-1)
    dy -= np.take(y, i, axis=-1)
    phi = np.arctan2(dy, dx)
    np.multiply(dx, dx, out=dx)
    np.multiply(dy, dy, out=dy)
    np.add(dx, dy, out=dx)
    distance = np.sqrt(dx, out=dx)
    return distance, _effort_from_phi(phi, np.take(yaw, i, axis=-1), np.take(yaw, j, axis=-1))


def batch_pair_features(
    position: np.ndarray,
    yaw: np.ndarray,
    *,
    features: Sequence[str] = DEFAULT_FEATURES,
    head_position: np.ndarray | None = None,
    head_yaw: np.ndarray | None = None,
    is_robot: np.ndarray | None = None,
    pairs: tuple[npt.ArrayLike, npt.ArrayLike] | None = None,
) -> np.ndarray:
    """Pair features of many frames with the same number of people, vectorised over both.

    Args:
        position: (F, n, 2) body positions, metres.
        yaw: (F, n) body yaws, radians.
        features: feature names, from :data:`FEATURES`.
        head_position: optional (F, n, 2) head positions, metres; NaN rows = unknown head.
        head_yaw: optional (F, n) head yaws, radians; NaN = unknown head.
        is_robot: optional (F, n) bool, which people are robots.
        pairs: optional ``(i, j)``, two (m,) arrays of rows: only these pairs, in this order,
            each with the same values as among all pairs (the frame's scale, for the
            scale-free features, is still that of all its people). None for all pairs.

    Returns:
        (F, n(n-1)/2, k) float64 features, pairs in :func:`pair_indices` order (or (F, m, k),
        the pairs given), columns in the order of ``features``.
    """
    features = check_features(features)
    position = np.asarray(position, dtype=np.float64)
    yaw = np.asarray(yaw, dtype=np.float64)
    if position.ndim != 3 or position.shape[2] != 2:
        raise ValueError(f"position must have shape (frames, people, 2), got {position.shape}")
    if yaw.shape != position.shape[:2]:
        raise ValueError(f"yaw must have shape {position.shape[:2]}, got {yaw.shape}")
    n_frames, n = yaw.shape
    if pairs is None:
        i, j = pair_indices(n)
    else:
        i, j = (np.asarray(rows, dtype=np.intp) for rows in pairs)
        if i.ndim != 1 or i.shape != j.shape:
            raise ValueError(f"pairs must be two (m,) arrays of rows, got {i.shape} and {j.shape}")
        if i.size and (min(i.min(), j.min()) < 0 or max(i.max(), j.max()) >= n):
            raise ValueError(f"pairs must hold rows in [0, {n}), got rows out of range")
    out = np.empty((n_frames, i.size, len(features)), dtype=np.float64)
    if i.size == 0:
        return out
    body = None
    head = None
    relative = None
    for column, name in enumerate(features):
        if name in (DISTANCE, EFFORT_ANGLE):
            if body is None:
                body = _distance_and_effort(position, yaw, i, j)
            out[..., column] = body[0] if name == DISTANCE else body[1]
        elif name in (HEAD_DISTANCE, HEAD_EFFORT_ANGLE):
            if head is None:
                head_pos, head_th = _head_or_body(position, yaw, head_position, head_yaw)
                head = _distance_and_effort(head_pos, head_th, i, j)
            out[..., column] = head[0] if name == HEAD_DISTANCE else head[1]
        elif name == INVOLVES_ROBOT:
            if is_robot is None:
                out[..., column] = 0.0
            else:
                robot = np.asarray(is_robot, dtype=bool)
                out[..., column] = robot[..., i] | robot[..., j]
        else:  # the scale-free features
            if relative is None:
                if body is None:
                    body = _distance_and_effort(position, yaw, i, j)
                scale = None if pairs is None else _own_scale(position)
                relative = _Relative(position, yaw, i, j, body[0], scale=scale)
            out[..., column] = relative.feature(name)
    return out


class _Relative:
    """The scale-free features of (F, n) frames' pairs, each computed when first asked for."""

    def __init__(
        self,
        position: np.ndarray,
        yaw: np.ndarray,
        i: np.ndarray,
        j: np.ndarray,
        distance: np.ndarray,
        *,
        scale: np.ndarray | None = None,
    ) -> None:
        self.position, self.yaw, self.i, self.j, self.distance = position, yaw, i, j, distance
        if scale is None:  # the pairs are all the pairs
            scale = _scale_from_pairs(position, distance, i, j)
        self.scale = scale[:, None]  # (F, 1)

    def feature(self, name: str) -> np.ndarray:
        if name == RELATIVE_DISTANCE:
            return self.distance / self.scale
        if name == OSPACE_DISTANCE:
            # (o_i - o_j) / s = (p_i - p_j) / s + OSPACE_STRIDE * (u_i - u_j)
            i, j, yaw = self.i, self.j, self.yaw
            delta = (self.position[:, i] - self.position[:, j]) / self.scale[..., None]
            delta[..., 0] += OSPACE_STRIDE * (np.cos(yaw[:, i]) - np.cos(yaw[:, j]))
            delta[..., 1] += OSPACE_STRIDE * (np.sin(yaw[:, i]) - np.sin(yaw[:, j]))
            return np.hypot(delta[..., 0], delta[..., 1])
        # LARGER_TURN: a_i = |wrap(phi_ij - theta_i)|, a_j = pi - |wrap(phi_ij - theta_j)|
        delta = self.position[:, self.j] - self.position[:, self.i]
        phi = np.arctan2(delta[..., 1], delta[..., 0])
        a_i = _fold(phi - self.yaw[:, self.i])
        a_j = np.pi - _fold(phi - self.yaw[:, self.j])
        return np.maximum(a_i, a_j)


def frame_scale(position: npt.ArrayLike) -> np.ndarray:
    """The scale of frames measured from the frames themselves: the median, over each frame's
    people, of the distance to their nearest neighbour (see the module notes).

    Args:
        position: (F, n, 2) positions, any unit; or (n, 2) for one frame.

    Returns:
        (F,) float64 scales in the positions' unit (a float for one frame). People whose nearest
        neighbour stands at the same spot are left out of the median; a frame with fewer than 2
        people, or where everyone shares a spot with someone, has scale 1.
    """
    position = np.asarray(position, dtype=np.float64)
    single = position.ndim == 2
    frames = position[None] if single else position
    if frames.ndim != 3 or frames.shape[2] != 2:
        raise ValueError(f"position must have shape (frames, people, 2), got {position.shape}")
    i, j = pair_indices(frames.shape[1])
    distance = np.hypot(*np.moveaxis(frames[:, j] - frames[:, i], -1, 0))
    scale = _scale_from_pairs(frames, distance, i, j)
    return float(scale[0]) if single else scale


def _scale_from_pairs(
    position: np.ndarray, distance: np.ndarray, i: np.ndarray, j: np.ndarray
) -> np.ndarray:
    """(F,) frame scales from (F, n, 2) positions and their (F, P) pair distances."""
    n_frames, n = position.shape[:2]
    if n < 2:
        return np.ones(n_frames)
    if n <= _SCALE_MATRIX_PEOPLE:
        matrix = np.full((n_frames, n, n), np.inf)
        matrix[:, i, j] = distance
        matrix[:, j, i] = distance
        nearest = matrix.min(axis=2)
    else:  # a large frame: a k-d tree per frame rather than an (n, n) matrix
        from scipy.spatial import cKDTree

        nearest = np.stack([cKDTree(frame).query(frame, k=2)[0][:, 1] for frame in position])
    nearest = np.where(nearest > 0, nearest, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a frame of people sharing spots
        scale = np.nanmedian(nearest, axis=1)
    return np.where(np.isfinite(scale) & (scale > 0), scale, 1.0)


def _own_scale(position: np.ndarray) -> np.ndarray:
    """(F,) frame scales of (F, n, 2) positions from all their pairs, computed as
    :func:`batch_pair_features` computes them for all pairs."""
    n = position.shape[1]
    i, j = pair_indices(n) if n <= _SCALE_MATRIX_PEOPLE else (np.zeros(0, np.intp),) * 2
    distance = _distance_and_effort(position, np.zeros(position.shape[:2]), i, j)[0]
    return _scale_from_pairs(position, distance, i, j)


def _head_or_body(
    position: np.ndarray,
    yaw: np.ndarray,
    head_position: np.ndarray | None,
    head_yaw: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    if head_position is None or head_yaw is None:
        return position, yaw
    head_position = np.asarray(head_position, dtype=np.float64)
    head_yaw = np.asarray(head_yaw, dtype=np.float64)
    missing = np.isnan(head_yaw)
    if not missing.any():
        return head_position, head_yaw
    return (
        np.where(missing[..., None], position, head_position),
        np.where(missing, yaw, head_yaw),
    )


def frame_arrays(frame: Frame, order: np.ndarray | None = None) -> dict[str, np.ndarray | None]:
    """The arrays of one frame that features need, rows in ``order`` (default: as stored)."""
    rows = slice(None) if order is None else order
    return {
        "position": frame.position[rows],
        "yaw": frame.yaw[rows],
        "head_position": None if frame.head_position is None else frame.head_position[rows],
        "head_yaw": None if frame.head_yaw is None else frame.head_yaw[rows],
        "is_robot": frame.is_robot[rows],
    }


def frame_pair_features(frame: Frame, *, features: Sequence[str] = DEFAULT_FEATURES) -> np.ndarray:
    """Pair features of one frame, pairs over its rows in :func:`pair_indices` order.

    Args:
        frame: the frame.
        features: feature names, from :data:`FEATURES`.

    Returns:
        (n(n-1)/2, k) float64 features.
    """
    arrays = frame_arrays(frame)
    head_position = arrays["head_position"]
    head_yaw = arrays["head_yaw"]
    return batch_pair_features(
        arrays["position"][None],
        arrays["yaw"][None],
        features=features,
        head_position=None if head_position is None else head_position[None],
        head_yaw=None if head_yaw is None else head_yaw[None],
        is_robot=arrays["is_robot"][None],
    )[0]

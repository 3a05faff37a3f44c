"""GCFF: Graph-Cuts for F-formations (Setti et al., PLoS ONE 2015), the field's reference detector.

A numpy re-implementation of the original MATLAB/C++ code (franzsetti/GCFF, ``gc.m`` with
``graphopt/expand.cpp``) that reproduces its partitions frame by frame on SALSA. Each person
votes for an o-space centre a ``stride`` in front of them (their *transactional-segment point*);
people whose points cluster around a common centre, and who can see that centre, form a group.

The energy of a labelling ``L`` (every person gets a candidate group) is::

    E(L) = sum_i U[i, L_i] + mdl * (number of distinct labels)

where ``U[i, k]`` is the squared distance from person ``i``'s segment point to the centre of
group ``k`` plus a *visibility penalty*: for every person ``j`` of the group's neighbourhood who
stands in front of ``i`` as seen from the centre (``cos > 0.75`` between their directions from
the centre, ``r_i > r_j``), ``U[i, k] += 100 ** (cos * r_i / r_j)``. The energy is minimised by
alpha-expansion with label costs; with no pairwise terms every expansion move has a closed form
(no max-flow needed). Centres are refitted and the expansion re-run until the labels settle (at
most 10 times).

Units — read this before choosing parameters:
    The visibility penalty ``100 ** (cos * r_i / r_j)`` is a pure number, but it is *added to
    squared distances*, so the value it is compared with depends on the length unit: GCFF in
    metres is not GCFF in centimetres. Every published parameter set (the original code's
    ``settings_gc.mat`` files: stride 50-70, mdl 6,000-30,000) assumes centimetres. This module
    therefore always computes in centimetres: positions (metres, as every ``Frame`` holds them)
    are multiplied by :data:`CM_PER_M`, and the parameters carry their units explicitly —
    :class:`Gcff` takes ``stride`` in metres and ``mdl`` in square metres (converted to cm and
    cm² inside), and :func:`gcff_labels` takes ``units="m"`` or ``"cm"``. The same scene in
    metres and in centimetres, with matching parameters, gives the same groups. The defaults,
    ``stride = 0.7 m`` and ``mdl = 1.0 m²``, are the reference code's ``stride = 70`` (cm) and
    ``mdl = 10000`` (cm²). The REFORM paper's "stride = 0.7, MDL = 30000" reads as 70 cm and
    30,000 cm² = 3.0 m².

Numerical fidelity:
    * the exponent of the visibility penalty is capped at :data:`MAX_VISIBILITY_EXPONENT`
      (``100 ** 100 = 1e200`` cm²). The original lets it overflow to infinity when someone stands
      almost exactly on a group's centre; the cap keeps every cost finite and changes no answer
      short of that degenerate case.
    * the energy of a labelling is summed in the reference code's order (person by person, then
      one ``mdl`` per used label). A move that swaps the two labels of a pair whose segment points
      define both centres changes the energy by exactly zero in real arithmetic; whether rounding
      calls it a decrease decides whether the sweep continues, and so, occasionally, the final
      partition. Summing in the same order reproduces the reference on every SALSA frame.
    * the sweep visits the candidate groups in the order of the people in the frame, as the
      reference follows the order of its input file, so reordering the people can change the
      answer (it does on 103 of 1,143 SALSA frames shuffled at random). The detector keeps the
      frame's row order; renaming the ids changes nothing.

Speed:
    :func:`gcff_labels` takes one of three paths by the frame's size, all with the same
    arithmetic in the same order, so all give the same labels: plain Python up to
    ``_PLAIN_PEOPLE`` (12) people, where numpy's per-call overhead would dominate; the dense
    windowed sweep up to ``_SPARSE_PEOPLE`` (64); beyond, the crowd sweep, which reads only the
    people a move can relabel, keeps the evaluations a kept move did not affect, and keeps the
    cost rows of groups whose members did not change from one refit to the next.

Example:
    >>> detector = Gcff(stride=0.7, mdl=1.0)          # doctest: +SKIP
    >>> detector.predict(dataset.annotated())[0]       # doctest: +SKIP
    ((1, 15), (2, 3, 5, 6, 7, 13), ...)
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from reform.estimator import Estimator, not_fitted_error
from reform.frame import POSITION_LIMIT_M, Frame, Group, check_frames

__all__ = [
    "CM_PER_M",
    "BASE_FRAME_BYTES",
    "CELL_BYTES",
    "frame_bytes",
    "MAX_FRAME_BYTES",
    "MAX_REFITS",
    "MAX_VISIBILITY_EXPONENT",
    "MDL_GRID_M2",
    "MDL_LIMIT_M2",
    "MDL_M2",
    "ORIENTATIONS",
    "STRIDE_GRID_M",
    "STRIDE_LIMIT_M",
    "STRIDE_M",
    "PEAK_DENSITY",
    "TRIPLE_BYTES",
    "UNITS",
    "VISIBILITY_BASE",
    "VISIBILITY_COSINE",
    "Expansion",
    "Gcff",
    "GcffBySequence",
    "GcffOwn",
    "GridSearch",
    "alpha_expansion",
    "energy",
    "gcff_labels",
    "grid_search",
    "labels_to_partition",
    "segment_points",
    "unary_costs",
]

CM_PER_M = 100.0  # centimetres per metre: GCFF computes in centimetres
UNITS = {"m": CM_PER_M, "cm": 1.0}  # centimetres per unit of length
STRIDE_M = 0.7  # metres; the reference code's stride = 70 (cm)
MDL_M2 = 1.0  # square metres; the reference code's mdl = 10000 (cm²)
# The largest stride and mdl GCFF takes: no larger than a position may be (POSITION_LIMIT_M),
# squared for an mdl, beyond which their squares overflow.
STRIDE_LIMIT_M = POSITION_LIMIT_M  # metres
MDL_LIMIT_M2 = POSITION_LIMIT_M**2  # square metres
VISIBILITY_COSINE = 0.75  # cosine above which one person hides another from the centre
VISIBILITY_BASE = 100.0  # the penalty is VISIBILITY_BASE ** (cos * r_i / r_j), in cm²
MAX_VISIBILITY_EXPONENT = 100.0  # cap on cos * r_i / r_j: penalty <= 1e200 cm²
MAX_REFITS = 10  # expansion + refit rounds, as the reference code's MAX_ITER
MAX_FRAME_BYTES = 8 * 2**30  # bytes: the most GCFF may take on one frame; a frame that would
# take more is refused, naming it, before the arrays are allocated
# Memory at the peak of one round, measured with tracemalloc on frames of 200 to 1,000 people:
CELL_BYTES = 32  # bytes per (person, candidate group) cell: the unary costs and the moves
PEAK_DENSITY = 5.0  # people per square metre: the most a crowd packs (a crush), for frame_bytes
BASE_FRAME_BYTES = 2**20  # bytes: what a frame costs GCFF whatever its people
TRIPLE_BYTES = 64  # bytes per (group, person, person) triple of the visibility penalty: every
# ordered pair of people within a group's neighbourhood, O(K·N²) in a dense crowd
_WINDOW = 32  # alpha-moves evaluated together (a speed setting; results do not depend on it)
_MATMUL_MAX_PEOPLE = 64  # up to this many people, per-label sums by a (small) matrix product
_SPARSE_PEOPLE = 64  # alpha_expansion on more people evaluates only who a move can relabel
_CHUNK_CELLS = 2**16  # cells of the (groups, people) temporaries computed at once
_PLAIN_PEOPLE = 12  # gcff_labels on at most this many people runs in plain Python (numpy's
# per-call overhead dominates there); the same arithmetic, operation for operation
_ROUNDING = 4 * np.finfo(np.float64).eps  # per term, a generous bound on a sum's rounding
ORIENTATIONS = ("body", "head")
# Default tuning grid: the published settings (stride 50-70 cm, mdl 6,000-30,000 cm²) and around.
STRIDE_GRID_M = (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)  # metres
MDL_GRID_M2 = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0)  # square metres


# --------------------------------------------------------------------------------------------
# The algorithm, in any consistent length unit (the detector feeds it centimetres)
# --------------------------------------------------------------------------------------------


def segment_points(position: npt.ArrayLike, yaw: npt.ArrayLike, *, stride: float) -> np.ndarray:
    """Transactional-segment points ``c_i = p_i + stride * (cos yaw_i, sin yaw_i)``.

    Args:
        position: (n, 2) ground-plane positions.
        yaw: (n,) orientations, radians counter-clockwise from +x.
        stride: distance in front of each person, same unit as ``position``.

    Returns:
        (n, 2) float64 points, same unit as ``position``.
    """
    position = np.asarray(position, dtype=np.float64)
    yaw = np.asarray(yaw, dtype=np.float64)
    points = np.empty_like(position)
    points[:, 0] = position[:, 0] + np.cos(yaw) * stride
    points[:, 1] = position[:, 1] + np.sin(yaw) * stride
    return points


class _TooLarge(ValueError):
    """A frame whose costs would take more than `MAX_FRAME_BYTES`."""


def _check_memory(n: int, n_groups: int, triples: int = 0) -> None:
    """Raises `_TooLarge` when ``n`` people, ``n_groups`` candidate groups and ``triples``
    visibility triples would take more than `MAX_FRAME_BYTES`."""
    needed = n * n_groups * CELL_BYTES + triples * TRIPLE_BYTES
    if needed > MAX_FRAME_BYTES:
        what = f"{n:,} people and {n_groups:,} candidate groups"
        if triples:
            what += f" with {triples:,} (group, person, person) visibility triples"
        raise _TooLarge(
            f"GCFF's costs for {what} would take about {needed / 2**30:,.1f} GiB, more than "
            f"reform.gcff.MAX_FRAME_BYTES = {MAX_FRAME_BYTES / 2**30:g} GiB"
        )


def frame_bytes(n_people: int, *, mdl: float = MDL_M2) -> int:
    """Bytes GCFF takes at its peak on one frame of ``n_people`` with ``mdl`` (square metres),
    as its own guard counts them (`MAX_FRAME_BYTES`): everyone a candidate group, and the
    visibility triples of people packed at `PEAK_DENSITY` (the triples of a frame denser than
    that are counted when it is solved, and refused there if too many), and `BASE_FRAME_BYTES`."""
    near = min(n_people, math.ceil(PEAK_DENSITY * math.pi * float(mdl)) + 1)
    return (
        n_people * n_people * CELL_BYTES + n_people * near * near * TRIPLE_BYTES + BASE_FRAME_BYTES
    )


def _renumber(labels: np.ndarray) -> np.ndarray:
    """Labels renamed 0..K-1 in increasing order of the old label."""
    _, inverse = np.unique(labels, return_inverse=True)
    return inverse.astype(np.int64).reshape(-1)


def unary_costs(
    points: npt.ArrayLike, position: npt.ArrayLike, labels: npt.ArrayLike, *, mdl: float
) -> np.ndarray:
    """Cost of assigning each person to each current group: squared distance + visibility.

    The centre of group ``k`` is the mean of its members' segment points. ``U[i, k]`` is the
    squared distance of ``points[i]`` to that centre; for the people within ``mdl`` of the centre
    (squared distance below ``mdl``), every person ``j`` of them who stands in front of ``i`` —
    ``r_i > r_j`` and ``cos > 0.75``, where ``r`` and ``cos`` are the distances and the angle of
    the *positions* seen from the centre — adds ``100 ** (cos * r_i / r_j)`` (exponent capped at
    :data:`MAX_VISIBILITY_EXPONENT`), whatever ``j``'s own label. Vectorised over the
    (group, person, person) triples inside the neighbourhoods, with the penalties of each cell
    added in increasing ``j`` as the reference code does.

    Args:
        points: (n, 2) segment points.
        position: (n, 2) positions, same unit.
        labels: (n,) int labels, already numbered 0..K-1 with every label used.
        mdl: squared length (the unit of ``points`` squared): neighbourhood radius squared.

    Returns:
        (n, K) float64 costs, in the squared unit.

    Raises:
        ValueError: costs that would take more than :data:`MAX_FRAME_BYTES`, before they are
            allocated (the (n, K) cells, then the neighbourhoods' triples).
    """
    return np.ascontiguousarray(_group_costs(points, position, labels, mdl=mdl).T)


class _CostBuffer:
    """A frame's (people x people) cost buffer, shared by its refits, and what its rows hold.

    Attributes:
        costs: (n, n) float64; rows 0..K-1 the costs of the last refit's groups.
        labels: (n,) the labels those rows were computed for, or None before the first refit.
        near: (n,) int64 neighbourhood size of each row's group (people within ``mdl``).
    """

    def __init__(self, n: int) -> None:
        self.costs = np.empty((n, n))
        self.labels: np.ndarray | None = None
        self.near = np.zeros(n, dtype=np.int64)


def _same_groups(
    previous: np.ndarray, labels: np.ndarray, n_groups: int, counts: np.ndarray
) -> np.ndarray:
    """For each group of ``labels``, the group of ``previous`` with exactly its members, or -1."""
    lowest = np.full(n_groups, np.iinfo(np.int64).max)
    highest = np.full(n_groups, -1)
    np.minimum.at(lowest, labels, previous)
    np.maximum.at(highest, labels, previous)
    before = np.bincount(previous, minlength=int(previous.max()) + 1)
    same = (lowest == highest) & (before[highest] == counts)
    return np.where(same, highest, -1)


def _group_costs(
    points: npt.ArrayLike,
    position: npt.ArrayLike,
    labels: npt.ArrayLike,
    *,
    mdl: float,
    buffer: _CostBuffer | None = None,
) -> np.ndarray:
    """:func:`unary_costs` transposed: (K, n), a row per group (the layout a crowd's
    alpha-moves read); the same values.

    With a ``buffer``, the costs are its first K rows, and a group whose members are exactly
    those of a group of the buffer's last refit takes that group's row as it is: a row is a
    function of its group's members alone (their mean segment point, then everyone's distance
    and visibility from it), so it is the row a new computation would give, bit for bit.
    """
    points = np.asarray(points, dtype=np.float64)
    position = np.asarray(position, dtype=np.float64)
    labels = np.asarray(labels, dtype=np.int64)
    n = labels.size
    n_groups = int(labels.max()) + 1 if n else 0
    _check_memory(n, n_groups)
    counts = np.bincount(labels, minlength=n_groups)
    centre_x = np.bincount(labels, weights=points[:, 0], minlength=n_groups) / counts
    centre_y = np.bincount(labels, weights=points[:, 1], minlength=n_groups) / counts
    todo = None  # the groups whose rows are computed; None: all, in place
    if buffer is None:
        costs = np.empty((n_groups, n))
        near = np.zeros(n_groups, dtype=np.int64)
    else:
        costs = buffer.costs[:n_groups]
        near = buffer.near
        if buffer.labels is not None:
            source = _same_groups(buffer.labels, labels, n_groups, counts)
            kept = np.flatnonzero(source >= 0)
            moved = kept[source[kept] != kept]
            # the right sides are copies, read before any row is written
            costs[moved] = buffer.costs[source[moved]]
            near[moved] = near[source[moved]]
            todo = np.flatnonzero(source < 0)
        buffer.labels = labels
    ids_all = np.arange(n_groups) if todo is None else todo
    # The rows a block of groups at a time: no (K, n) temporaries
    rows = max(1, _CHUNK_CELLS // max(n, 1))
    dx = np.empty((min(rows, ids_all.size), n))
    dy = np.empty_like(dx)
    entries = []  # flat (group, person) indices of the neighbourhoods, by group then person
    for lo in range(0, ids_all.size, rows):
        ids = ids_all[lo : lo + rows]
        part = costs[lo : lo + ids.size] if todo is None else dx[: ids.size]
        block = dy[: ids.size]
        np.subtract(points[None, :, 0], centre_x[ids, None], out=part)
        np.multiply(part, part, out=part)
        np.subtract(points[None, :, 1], centre_y[ids, None], out=block)
        np.multiply(block, block, out=block)
        np.add(part, block, out=part)  # dx * dx + dy * dy
        row, person = np.nonzero(part < mdl)
        near[ids] = np.bincount(row, minlength=ids.size)
        entries.append(ids[row] * n + person)
        if todo is not None:
            costs[ids] = part
    del dx, dy

    # Neighbourhood entries (k, i), ordered by group then person (np.nonzero's order).
    group, person = np.divmod(np.concatenate(entries) if entries else np.zeros(0, int), n)
    _check_memory(n, n_groups, int(np.dot(near[:n_groups], near[:n_groups])))
    if group.size == 0:
        return costs
    vx = position[person, 0] - centre_x[group]
    vy = position[person, 1] - centre_y[group]
    radius = np.sqrt(vx * vx + vy * vy)
    # Every ordered pair (behind, front) of entries of the same group, behind-major, front
    # ascending: the order in which the reference adds the penalties.
    size = np.bincount(group, minlength=n_groups)
    start = np.concatenate(([0], np.cumsum(size)[:-1]))
    repeats = size[group]
    behind = np.repeat(np.arange(group.size), repeats)
    first = np.repeat(np.cumsum(repeats) - repeats, repeats)
    front = start[group[behind]] + (np.arange(behind.size) - first)
    r_behind = radius[behind]
    r_front = radius[front]
    with np.errstate(divide="ignore", invalid="ignore"):
        cosine = (vx[behind] * vx[front] + vy[behind] * vy[front]) / (r_behind * r_front)
        hidden = (r_behind > r_front) & (cosine > VISIBILITY_COSINE)
        exponent = cosine[hidden] * r_behind[hidden] / r_front[hidden]
    exponent = np.minimum(exponent, MAX_VISIBILITY_EXPONENT)
    penalty = VISIBILITY_BASE**exponent
    cell = group[behind[hidden]] * n + person[behind[hidden]]
    flat = costs.reshape(-1)
    np.add.at(flat, cell, penalty)  # unbuffered and in order: sequential per cell
    return costs


def energy(unary: npt.ArrayLike, labels: npt.ArrayLike, *, label_cost: float) -> float:
    """``E(L) = sum_i U[i, L_i] + label_cost * #distinct labels``, summed as the reference does.

    The reference code adds the costs person by person, then one ``label_cost`` per used label;
    the same order is kept here so that exact ties round the same way.
    """
    unary = np.asarray(unary, dtype=np.float64)
    labels = np.asarray(labels, dtype=np.int64)
    terms = np.concatenate(
        (
            unary[np.arange(labels.size), labels],
            np.full(np.unique(labels).size, float(label_cost)),
        )
    )
    return float(np.cumsum(terms)[-1]) if terms.size else 0.0


@dataclass(frozen=True)
class Expansion:
    """Result of :func:`alpha_expansion`.

    Attributes:
        labels: (n,) int64 final labels (columns of the unary matrix; not renumbered).
        energies: energy before the first move, then after every accepted move (non-increasing).
        moves: number of alpha-moves tried, accepted or not.
    """

    labels: np.ndarray
    energies: tuple[float, ...]
    moves: int


def _moves(
    unary: np.ndarray,
    labels: np.ndarray,
    alphas: np.ndarray | None,
    label_cost: float,
    label_costs: np.ndarray,
    identity: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The alpha-moves for several alphas at once, all from the same ``labels``.

    Per-label sums: a one-hot matrix product for few people; for many, a sort and
    ``np.add.reduceat`` (O(n·m) work, and no large BLAS call, whose threads thrash on a busy
    machine).

    Args:
        unary: (n, K) costs.
        labels: (n,) current labels.
        alphas: (m,) the alphas to evaluate, or None for all K in order.
        label_cost: cost of one used label.
        label_costs: (K + 1, K) ``label_cost * (j < u)`` at ``[u, j]``: the label costs added
            last for a labelling with ``u`` used labels.
        identity: (K, K) float identity (one-hot rows).

    Returns:
        moved: (n, m) bool, column ``j`` the people that the move of ``alphas[j]`` relabels.
        changed: (m,) bool, whether that move changes any label.
        energies: (m,) float64 energy after that move (summed as :func:`energy` does).
    """
    n = labels.size
    rows = np.arange(n)
    few = n <= _MATMUL_MAX_PEOPLE
    if few:
        # Few people: sums through a one-hot matrix product (BLAS, single-threaded at this size).
        # Rows of unused labels sum to 0, so they always "close": counted out below.
        one_hot = identity[labels]  # (n, K)
        used = one_hot.any(axis=0)
        group = labels
    else:
        order = np.argsort(labels, kind="stable")
        ordered = labels[order]
        first = np.empty(n, dtype=bool)
        first[0] = True
        np.not_equal(ordered[1:], ordered[:-1], out=first[1:])
        starts = np.flatnonzero(first)  # where each used label's members begin in ``order``
        group = np.empty(n, dtype=np.int64)  # each person's used label, numbered 0..u-1
        group[order] = np.cumsum(first) - 1
        used = np.zeros(unary.shape[1], dtype=bool)
        used[ordered[starts]] = True
    current = unary[rows, labels]
    target = unary if alphas is None else unary[:, alphas]
    delta = target - current[:, None]  # d_i for every alpha, (n, m)
    # Per (used label l, alpha): option A moves the members with d <= 0 (l stays open, its
    # cost paid), option B moves all of S_l (l closes, its cost saved). B is taken when it
    # costs no more than A: when the positive d of the members sum to at most the label cost.
    positive = np.maximum(delta, 0.0)
    if few:
        sums = one_hot.T @ positive
    else:
        sums = np.add.reduceat(positive[order], starts, axis=0)
    take_all = sums <= label_cost  # (K or u, m), by label
    moved = take_all[group]
    moved |= delta <= 0.0
    if alphas is None:
        moved[rows, labels] = False  # people already labelled alpha stay
    else:
        moved &= labels[:, None] != alphas[None, :]
    changed = moved.any(axis=0)
    # Labels used after each move: the labels that B closes go (alpha's own d are all 0, so it
    # counts as closed when used, and is added back; unused rows count as closed and cancel
    # out), and alpha opens when unused and gaining members.
    alpha_used = used if alphas is None else used[alphas]
    n_used = (take_all.shape[0] - np.count_nonzero(take_all, axis=0)) + (alpha_used | changed)
    # Energies summed in the reference order: person by person, then one cost per used label.
    terms = np.empty((moved.shape[1], n + label_costs.shape[1]))
    np.copyto(terms[:, :n], np.where(moved, target, current[:, None]).T)
    terms[:, n:] = label_costs[n_used]
    return moved, changed, np.add.accumulate(terms, axis=1)[:, -1]


def alpha_expansion(unary: npt.ArrayLike, labels: npt.ArrayLike, *, label_cost: float) -> Expansion:
    """Minimises ``sum_i U[i, L_i] + label_cost * #labels`` by alpha-expansion with label costs.

    Sweeps ``alpha = 0, 1, ..., K-1`` cyclically. One alpha-move considers every used label
    ``l != alpha`` with members ``S_l`` and ``d_i = U[i, alpha] - U[i, l]``: either the members
    with ``d_i <= 0`` move to alpha (``l`` stays open; cost ``sum_{d_i<0} d_i + label_cost``) or
    all of ``S_l`` moves (``l`` closes; cost ``sum d_i``), whichever is cheaper (all on a tie).
    This is the exact minimiser of the graph cut the reference builds: with no pairwise terms
    the cut decomposes label by label. The move ignores alpha's own label cost; it is kept only
    when the full energy did not increase. The sweep stops after K consecutive moves without a
    strict decrease.

    The next :data:`_WINDOW` moves are evaluated at once (vectorised) from the current labels,
    so Python work is spent per *accepted* move, not per move tried; the result is identical to
    trying them one by one.

    Args:
        unary: (n, K) costs, finite.
        labels: (n,) starting labels in 0..K-1.
        label_cost: cost of each used label (``mdl``), same unit as ``unary``.

    Returns:
        The final labels, the energies along the way and the number of moves tried.
    """
    unary = np.asarray(unary, dtype=np.float64)
    labels = np.array(labels, dtype=np.int64).reshape(-1)
    n, k = unary.shape
    if labels.shape != (n,):
        raise ValueError(f"labels must have shape ({n},), got {labels.shape}")
    if n and (labels.min() < 0 or labels.max() >= k):
        raise ValueError(f"labels must lie in [0, {k - 1}], got {labels.min()}..{labels.max()}")
    if not (np.isfinite(unary.sum()) or np.all(np.isfinite(unary))):  # a sum first: no temporary
        raise ValueError("unary must be finite, got NaN or inf")
    label_cost = float(label_cost)
    if not (np.isfinite(label_cost) and label_cost >= 0.0):
        raise ValueError(f"label_cost must be a finite number >= 0, got {label_cost!r}")
    if n > _SPARSE_PEOPLE:
        return _sparse_expansion(unary, labels, label_cost)
    identity = np.eye(k) if n <= _MATMUL_MAX_PEOPLE else np.empty((0, 0))
    label_costs = np.tri(k + 1, k, -1) * label_cost  # [u, j] = label_cost if j < u
    whole = k <= _WINDOW  # evaluate every alpha in column order; scan from the current one
    window = np.arange(min(k, _WINDOW))
    current = energy(unary, labels, label_cost=label_cost)
    energies = [current]
    alpha = 0
    stale = 0  # consecutive moves without a strict decrease
    moves = 0
    while stale < k:
        if whole:
            moved, changed, candidate = _moves(
                unary, labels, None, label_cost, label_costs, identity
            )
            order = list(range(alpha, k)) + list(range(alpha))
            columns = order
        else:
            alphas = (alpha + window) % k
            moved, changed, candidate = _moves(
                unary, labels, alphas, label_cost, label_costs, identity
            )
            order = alphas.tolist()
            columns = range(len(order))
        changed_list = changed.tolist()
        candidate_list = candidate.tolist()
        for a, j in zip(order, columns, strict=True):
            alpha = (a + 1) % k
            moves += 1
            if changed_list[j] and candidate_list[j] <= current:
                e = candidate_list[j]
                stale = 0 if e < current else stale + 1
                labels = np.where(moved[:, j], a, labels)
                current = e
                energies.append(current)
                break
            stale += 1  # no change, or rejected because the energy would rise
            if stale >= k:
                break
    return Expansion(labels=labels, energies=tuple(energies), moves=moves)


def _sparse_expansion(unary: np.ndarray, labels: np.ndarray, label_cost: float) -> Expansion:
    """:func:`alpha_expansion` for many people, evaluating only the people a move can relabel.

    The same sweep, windows and decisions as the dense form, with two facts that make a move's
    work grow with the people near its alpha rather than with everyone:

    * a person ``i`` whom the move of ``alpha`` relabels has ``d_i <= label_cost`` (either
      ``d_i <= 0``, or their whole label moves, whose positive ``d`` sum to at most
      ``label_cost``, each at most their sum): the others are never looked at, and a label
      with such a member never moves whole. The labels' sums are those of the dense form (the
      same members' values in the same order, summed by the same ``np.add.reduceat``).
    * a move is kept when its energy, summed term by term in the reference order, is not above
      the current one. Its exact change is the sum of the moved people's ``d`` and the label
      costs it opens or closes; where that change is farther from zero than the rounding of the
      two sums can reach (bounded by ``n + K`` terms' rounding of their absolute sum), the
      comparison is decided by its sign; only closer calls sum the energy in full.
    * a move's evaluation reads only the people within its reach, their labels and those
      labels' sizes (and alpha's own). After a move is kept, the window's later moves that read
      none of what it changed (the people it moved, their old labels, alpha) and that none of
      the moved people can now reach keep their evaluation; the sweep goes on with them and
      evaluates a new window only from the first move that must be evaluated again. The
      global terms (labels in use, the sum of the costs that bounds the rounding) are read
      afresh at every decision, so each decision is the one a fresh evaluation would make.
    """
    n, k = unary.shape
    by_group = np.ascontiguousarray(unary.T)  # (K, n): no copy for gcff_labels' costs
    cost = unary[np.arange(n), labels]  # each person's current cost
    size = np.bincount(labels, minlength=k)
    used = int(np.count_nonzero(size))
    current = energy(unary, labels, label_cost=label_cost)
    energies = [current]
    terms = n + k
    steps = np.arange(min(k, _WINDOW))
    d_buffer = np.empty((steps.size, n))  # a window's d
    reach_buffer = np.empty((steps.size, n), dtype=bool)
    moved_person = np.zeros(n, dtype=bool)  # scratch marks, cleared after each use
    touched_label = np.zeros(k, dtype=bool)
    alpha = 0
    stale = 0
    moves = 0
    while stale < k:
        alphas = (alpha + steps) % k
        m = alphas.size
        # d of every (window place, person); the move of alpha may relabel only d <= label_cost
        rows = by_group[alpha : alpha + m] if alpha + m <= k else by_group[alphas]
        d_all = np.subtract(rows, cost, out=d_buffer[:m])
        reach = np.flatnonzero(np.less_equal(d_all, label_cost, out=reach_buffer[:m]))
        entry_alpha, person = np.divmod(reach, n)  # by place, then person
        delta = d_all.reshape(-1)[reach]
        label = labels[person]
        # Per (window place, label) groups, members in person order.
        key = entry_alpha * k + label
        order = np.argsort(key, kind="stable")
        key_sorted = key[order]
        boundary = np.empty(key.size, dtype=bool)
        boundary[:1] = True
        np.not_equal(key_sorted[1:], key_sorted[:-1], out=boundary[1:])
        opens = np.flatnonzero(boundary)
        group_alpha, group_label = np.divmod(key_sorted[opens], k)
        counts = np.diff(opens, append=key.size)
        sums = np.add.reduceat(np.maximum(delta[order], 0.0), opens) if key.size else delta[:0]
        take_all = (counts == size[group_label]) & (sums <= label_cost)
        group_of = np.empty(key.size, dtype=np.intp)
        group_of[order] = np.repeat(np.arange(opens.size), counts)
        moved = (delta <= 0.0) | take_all[group_of]
        moved &= label != alphas[entry_alpha]
        moved_alpha = entry_alpha[moved]
        moved_delta = delta[moved]
        changed = np.bincount(moved_alpha, minlength=m) > 0
        closed = np.bincount(group_alpha[take_all], minlength=m)
        opened = ((size[alphas] > 0) | changed).astype(np.int64) - closed  # labels in use, more
        change = np.bincount(moved_alpha, weights=moved_delta, minlength=m).astype(float)
        change += label_cost * opened
        spread = np.bincount(moved_alpha, weights=np.abs(moved_delta), minlength=m)
        spread = spread.astype(float) + label_cost * np.abs(opened)
        changed_list = changed.tolist()
        change_list = change.tolist()
        spread_list = spread.tolist()
        opened_list = opened.tolist()
        alpha_list = alphas.tolist()
        total = float(np.abs(cost).sum()) + used * label_cost  # sum of |terms| now
        place_start = np.searchsorted(entry_alpha, np.arange(m + 1)).tolist()
        valid = m  # places from here on must be evaluated again
        j = 0
        while j < valid and stale < k:
            a = alpha_list[j]
            alpha = (a + 1) % k
            moves += 1
            accept = False
            if changed_list[j]:
                slack = _ROUNDING * terms * (2 * total + spread_list[j] + abs(change_list[j]))
                if change_list[j] < -slack:
                    accept = True
                elif change_list[j] > slack:
                    accept = False
                else:  # a close call: the energy summed as the reference sums it
                    who = person[moved & (entry_alpha == j)]
                    after = cost.copy()
                    after[who] = by_group[a, who]
                    accept = _energy_of(after, used + opened_list[j], label_cost) <= current
            if not accept:
                stale += 1  # no change, or rejected because the energy would rise
                j += 1
                continue
            who = person[moved & (entry_alpha == j)]
            touched = np.append(labels[who], a)  # labels whose members or size change
            np.subtract.at(size, labels[who], 1)
            size[a] += who.size
            labels[who] = a
            cost[who] = by_group[a, who]
            used += opened_list[j]
            e = _energy_of(cost, used, label_cost)
            stale = 0 if e < current else stale + 1
            current = e
            energies.append(current)
            total = float(np.abs(cost).sum()) + used * label_cost
            j += 1
            if j < valid:  # the later places that read anything this move changed
                moved_person[who] = True
                touched_label[touched] = True
                rest = alphas[j:valid]
                lo, hi = place_start[j], place_start[valid]
                hit = moved_person[person[lo:hi]] | touched_label[label[lo:hi]]
                dirty = touched_label[rest]
                dirty[entry_alpha[lo:hi][hit] - j] = True
                dirty |= (by_group[rest[:, None], who[None, :]] - cost[who] <= label_cost).any(1)
                moved_person[who] = False
                touched_label[touched] = False
                first = np.flatnonzero(dirty)
                if first.size:
                    valid = j + int(first[0])
    return Expansion(labels=labels, energies=tuple(energies), moves=moves)


def _energy_of(cost: np.ndarray, used: int, label_cost: float) -> float:
    """The energy of per-person costs ``cost`` and ``used`` labels, summed as :func:`energy`
    sums it (person by person, then one ``label_cost`` per used label)."""
    return float(np.add.accumulate(np.concatenate([cost, np.full(used, label_cost)]))[-1])


# --------------------------------------------------------------------------------------------
# Few people: the same computation in plain Python
# --------------------------------------------------------------------------------------------


def _plain_labels(position: np.ndarray, points: np.ndarray, mdl: float) -> np.ndarray:
    """:func:`gcff_labels`' refit loop for a few people, in plain Python.

    Every cost, sum and comparison is the one the numpy path makes, in the same order (sums
    left to right, as ``np.bincount``, ``np.cumsum`` and the one-hot product of :func:`_moves`
    add), so the labels are identical; only numpy's per-call overhead is saved.

    Args:
        position: (n, 2) positions, centimetres.
        points: (n, 2) segment points, centimetres.
        mdl: label cost and neighbourhood radius squared, cm².

    Returns:
        (n,) int64 labels, renumbered.
    """
    pos = position.tolist()
    pts = points.tolist()
    labels = list(range(len(pts)))
    for _ in range(MAX_REFITS):
        costs = _plain_unary(pts, pos, labels, mdl)
        moved = _plain_expansion(costs, labels, mdl)
        rank = {label: r for r, label in enumerate(sorted(set(moved)))}
        expanded = [rank[label] for label in moved]
        if expanded == labels:
            break
        labels = expanded
    return np.array(labels, dtype=np.int64)


def _plain_unary(
    pts: list[list[float]], pos: list[list[float]], labels: list[int], mdl: float
) -> list[list[float]]:
    """:func:`unary_costs` in plain Python: (n, K) nested lists, the same values bit for bit."""
    n = len(labels)
    k = max(labels) + 1
    sum_x, sum_y, count = [0.0] * k, [0.0] * k, [0] * k
    for (x, y), label in zip(pts, labels, strict=True):
        sum_x[label] += x
        sum_y[label] += y
        count[label] += 1
    centre_x = [sx / c for sx, c in zip(sum_x, count, strict=True)]
    centre_y = [sy / c for sy, c in zip(sum_y, count, strict=True)]
    costs = []
    for x, y in pts:
        row = []
        for cx, cy in zip(centre_x, centre_y, strict=True):
            dx = x - cx
            dy = y - cy
            row.append(dx * dx + dy * dy)
        costs.append(row)
    cells: list[tuple[int, int]] = []  # (person, group) of each penalty, in the order added
    exponents: list[float] = []
    for g in range(k):
        cx, cy = centre_x[g], centre_y[g]
        near = []  # (person, vx, vy, r), persons ascending
        for i in range(n):
            if costs[i][g] < mdl:
                vx = pos[i][0] - cx
                vy = pos[i][1] - cy
                near.append((i, vx, vy, math.sqrt(vx * vx + vy * vy)))
        if len(near) < 2:
            continue
        for i, bx, by, rb in near:  # behind
            for _, fx, fy, rf in near:  # in front, ascending
                if rb > rf:
                    cosine = _divide(bx * fx + by * fy, rb * rf)
                    if cosine > VISIBILITY_COSINE:
                        cells.append((i, g))
                        exponents.append(min(cosine * rb / rf, MAX_VISIBILITY_EXPONENT))
    if cells:
        # numpy's power, as the numpy path takes it (it may differ from libm's in the last bit)
        penalties = (VISIBILITY_BASE ** np.array(exponents)).tolist()
        for (i, g), penalty in zip(cells, penalties, strict=True):
            costs[i][g] += penalty
    return costs


def _divide(numerator: float, denominator: float) -> float:
    """``numerator / denominator`` as numpy divides: 0/0 is NaN, x/0 an infinity."""
    if denominator == 0.0:
        if numerator == 0.0 or numerator != numerator:
            return math.nan
        return math.copysign(math.inf, numerator) * math.copysign(1.0, denominator)
    return numerator / denominator


def _plain_expansion(costs: list[list[float]], labels: list[int], label_cost: float) -> list[int]:
    """:func:`alpha_expansion`'s labels in plain Python, one alpha-move at a time.

    Per-label sums of the positive ``d`` run over the people in order, as the one-hot product
    of :func:`_moves` sums them (at most :data:`_MATMUL_MAX_PEOPLE` people); energies are
    summed person by person, then one ``label_cost`` per used label, as :func:`energy` does.
    """
    k = len(costs[0])
    labels = list(labels)
    cost = [costs[i][label] for i, label in enumerate(labels)]
    current = _plain_energy(cost, len(set(labels)), label_cost)
    alpha = 0
    stale = 0
    while stale < k:
        a = alpha
        alpha = (a + 1) % k
        target = [row[a] for row in costs]
        delta = [t - c for t, c in zip(target, cost, strict=True)]
        sums: dict[int, float] = {}
        for label, d in zip(labels, delta, strict=True):
            sums[label] = sums.get(label, 0.0) + (d if d > 0.0 else 0.0)
        take_all = {label: total <= label_cost for label, total in sums.items()}
        moved = [
            label != a and (take_all[label] or d <= 0.0)
            for label, d in zip(labels, delta, strict=True)
        ]
        if not any(moved):
            stale += 1
            continue
        used = sum(1 for label, whole in take_all.items() if label != a and not whole) + 1
        after = [t if m else c for t, c, m in zip(target, cost, moved, strict=True)]
        candidate = _plain_energy(after, used, label_cost)
        if candidate <= current:
            stale = 0 if candidate < current else stale + 1
            labels = [a if m else label for label, m in zip(labels, moved, strict=True)]
            cost = after
            current = candidate
        else:
            stale += 1
    return labels


def _plain_energy(cost: list[float], used: int, label_cost: float) -> float:
    """:func:`energy` of these per-person costs and ``used`` labels, summed in its order."""
    total = 0.0
    for c in cost:
        total += c
    for _ in range(used):
        total += label_cost
    return total


def gcff_labels(
    position: npt.ArrayLike,
    yaw: npt.ArrayLike,
    *,
    stride: float,
    mdl: float,
    units: str = "m",
) -> np.ndarray:
    """GCFF on one frame: a group label per person.

    Args:
        position: (n, 2) ground-plane positions, in ``units``.
        yaw: (n,) orientations, radians counter-clockwise from +x (wrapped or not).
        stride: distance of the o-space centre in front of each person, in ``units``.
        mdl: cost of opening one more group, in ``units`` squared.
        units: ``"m"`` or ``"cm"``; the computation runs in centimetres either way (see the
            module docstring: the visibility penalty is not scale-free).

    Returns:
        (n,) int64 labels 0..K-1 (renumbered as the reference code does); people sharing a label
        form a group, a label of its own is a singleton.

    Raises:
        ValueError: bad arrays or parameters, or a frame whose costs would take more than
            :data:`MAX_FRAME_BYTES` (checked before they are allocated).
    """
    scale = _centimetres_per(units)
    position = np.asarray(position, dtype=np.float64)
    yaw = np.asarray(yaw, dtype=np.float64)
    n = position.shape[0] if position.ndim == 2 else -1
    if position.shape != (n, 2) or n < 0:
        raise ValueError(f"position must have shape (n, 2), got {position.shape}")
    if yaw.shape != (n,):
        raise ValueError(f"yaw must have shape ({n},), got {yaw.shape}")
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(yaw))):
        raise ValueError("position and yaw must be finite, got NaN or inf")
    _check_positive("stride", stride, allow_zero=True)
    _check_positive("mdl", mdl)
    position_cm = position * scale if scale != 1.0 else position
    stride_cm = _convert(stride, scale)
    mdl_cm2 = _convert(mdl, scale * scale)
    labels = np.arange(n, dtype=np.int64)
    if n <= 1:
        return labels
    _check_memory(n, n)  # every person starts as a candidate group
    points = segment_points(position_cm, yaw, stride=stride_cm)
    if n <= _PLAIN_PEOPLE:
        return _plain_labels(position_cm, points, mdl_cm2)
    # A crowd's costs: a row per group, as its moves read them, in one buffer for every refit
    # (groups only merge: K <= n).
    buffer = _CostBuffer(n) if n > _SPARSE_PEOPLE else None
    for _ in range(MAX_REFITS):
        if buffer is not None:
            unary = _group_costs(points, position_cm, labels, mdl=mdl_cm2, buffer=buffer).T
        else:
            unary = unary_costs(points, position_cm, labels, mdl=mdl_cm2)
        expanded = _renumber(alpha_expansion(unary, labels, label_cost=mdl_cm2).labels)
        if np.array_equal(expanded, labels):
            break
        labels = expanded
    return labels


def labels_to_partition(ids: npt.ArrayLike, labels: npt.ArrayLike) -> tuple[Group, ...]:
    """A full partition from per-person labels: groups in order of their first member's row,
    members in row order, singletons included."""
    ids = np.asarray(ids).tolist()
    groups: dict[int, list[int]] = {}
    for person, label in zip(ids, np.asarray(labels).tolist(), strict=True):
        groups.setdefault(label, []).append(int(person))
    return tuple(tuple(members) for members in groups.values())


def _centimetres_per(units: str) -> float:
    """Centimetres per one of ``units`` (`UNITS`), or a ValueError naming those accepted."""
    if units not in UNITS:
        raise ValueError(f"units must be one of {sorted(UNITS)}, got {units!r}")
    return UNITS[units]


def _convert(value: float, factor: float) -> float:
    """``value * factor`` on the decimal the user wrote: 0.7 m -> 70 cm, not 70.00000000000001."""
    if factor == 1.0:
        return float(value)
    return float(Decimal(repr(float(value))) * Decimal(repr(float(factor))))


def _check_positive(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """A stride (metres, ``allow_zero``) or an mdl (square metres) as a float, or a ValueError:
    finite, not negative, and at most :data:`STRIDE_LIMIT_M` (:data:`MDL_LIMIT_M2`)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    high = STRIDE_LIMIT_M if allow_zero else MDL_LIMIT_M2
    bad = not np.isfinite(number) or number < 0 or (number == 0 and not allow_zero)
    if bad or number > high:
        expected = "a finite number >= 0" if allow_zero else "a finite number > 0"
        raise ValueError(f"{name} must be {expected} and <= {high:g}, got {value!r}")
    return number


# --------------------------------------------------------------------------------------------
# The detector
# --------------------------------------------------------------------------------------------


def _orientation(frame: Frame, orientation: str) -> np.ndarray:
    if orientation == "body" or frame.head_yaw is None:
        if orientation == "head":
            raise ValueError(
                f"orientation='head' needs head yaws, but the frame at time {frame.time:g} s"
                f"{f' of {frame.sequence!r}' if frame.sequence else ''} has none"
            )
        return frame.yaw
    return np.where(np.isfinite(frame.head_yaw), frame.head_yaw, frame.yaw)


def _predict(
    frames: Sequence[Frame], *, stride: float, mdl: float, orientation: str
) -> list[tuple[Group, ...]]:
    for frame in frames:  # the largest frames refused before any is computed
        try:
            _check_memory(frame.n_people, frame.n_people)
        except _TooLarge as exc:
            raise ValueError(f"{_frame_text(frame)}: {exc}") from None
    partitions = []
    for frame in frames:
        try:
            labels = gcff_labels(
                frame.position,
                _orientation(frame, orientation),
                stride=stride,
                mdl=mdl,
                units="m",
            )
        except _TooLarge as exc:  # a crowd too dense for the visibility penalty
            raise ValueError(f"{_frame_text(frame)}: {exc}") from None
        partitions.append(labels_to_partition(frame.ids, labels))
    return partitions


def _frame_text(frame: Frame) -> str:
    """``the frame at time 3.5 s of sequence 'x' (2,000 people)``, for messages."""
    sequence = f" of sequence {frame.sequence!r}" if frame.sequence else ""
    return f"the frame at time {frame.time:g} s{sequence} ({frame.n_people:,} people)"


@dataclass(frozen=True)
class GridSearch:
    """Scores of every (stride, mdl) setting tried by :func:`grid_search`.

    Attributes:
        stride: (n_settings,) float64 strides tried, metres.
        mdl: (n_settings,) float64 mdl values tried, square metres.
        f1: (n_settings,) float64 objective: F1 of the frame means at ``threshold``.
        threshold: the matching threshold of the objective.
        best: index of the chosen setting (highest F1; the first in grid order on a tie).
        n_frames: annotated frames scored.
    """

    stride: np.ndarray
    mdl: np.ndarray
    f1: np.ndarray
    threshold: Fraction
    best: int
    n_frames: int

    @property
    def best_stride(self) -> float:
        """Chosen stride, metres."""
        return float(self.stride[self.best])

    @property
    def best_mdl(self) -> float:
        """Chosen mdl, square metres."""
        return float(self.mdl[self.best])

    @property
    def best_f1(self) -> float:
        """Objective at the chosen setting."""
        return float(self.f1[self.best])


def grid_search(
    frames: Sequence[Frame],
    *,
    stride_grid: Sequence[float] = STRIDE_GRID_M,
    mdl_grid: Sequence[float] = MDL_GRID_M2,
    orientation: str = "body",
    threshold: Any = Fraction(2, 3),
) -> GridSearch:
    """Picks ``stride`` and ``mdl`` maximising the protocol's F1 on annotated training frames.

    The objective is :func:`reform.metrics.evaluate`'s F1 of the frame-mean precision and
    recall at ``threshold``. Only ``frames`` are used; pass training frames only.

    Args:
        frames: training frames; frames without ground truth are ignored.
        stride_grid: strides to try, metres.
        mdl_grid: mdl values to try, square metres.
        orientation: ``"body"`` or ``"head"``.
        threshold: matching threshold of the objective (``Fraction``, ``"2/3"`` or 1).

    Returns:
        Every setting's score and the chosen one.
    """
    from reform.metrics import evaluate

    annotated = [f for f in check_frames(frames) if f.groups is not None]
    if not annotated:
        raise ValueError("frames must include annotated frames to tune on, got none")
    strides = [_check_positive("stride_grid entry", s, allow_zero=True) for s in stride_grid]
    mdls = [_check_positive("mdl_grid entry", m) for m in mdl_grid]
    if not strides or not mdls:
        raise ValueError("stride_grid and mdl_grid must each hold at least one value, got none")
    grid = [(s, m) for s in strides for m in mdls]
    scores = []
    for stride, mdl in grid:
        predictions = _predict(annotated, stride=stride, mdl=mdl, orientation=orientation)
        scores.append(evaluate(annotated, predictions, thresholds=(threshold,)).at(threshold).f1)
    f1 = np.asarray(scores, dtype=np.float64)
    return GridSearch(
        stride=np.array([s for s, _ in grid]),
        mdl=np.array([m for _, m in grid]),
        f1=f1,
        threshold=Fraction(threshold),
        best=int(np.argmax(f1)),
        n_frames=len(annotated),
    )


class Gcff(Estimator):
    """GCFF detector (Setti et al. 2015), faithful to the reference code, in metres.

    Follows the detector protocol: ``fit(frames) -> self`` and ``predict(frames)`` -> one full
    partition per frame (groups of person ids, singletons included). With ``tune=False`` there
    is nothing to learn: ``fit`` only validates and ``predict`` works on a fresh instance. With
    ``tune=True``, ``fit`` grid-searches ``stride`` and ``mdl`` on the training frames with the
    evaluation protocol's F1 as the objective (:func:`grid_search`).

    Units: ``stride`` is in metres and ``mdl`` in square metres; the computation runs in
    centimetres (the visibility penalty is not scale-free; see the module docstring). The
    defaults equal the reference code's ``stride = 70`` cm, ``mdl = 10000`` cm².

    Args:
        stride: distance of the o-space centre in front of each person, metres.
        mdl: cost of opening one more group, square metres (10,000 cm² = 1 m²).
        orientation: ``"body"`` (the reference's choice) or ``"head"`` (head yaw where
            observed, body yaw for people whose head is not; positions are body positions).
        tune: grid-search ``stride`` and ``mdl`` in ``fit`` instead of using the given ones.
        stride_grid: strides tried when tuning, metres.
        mdl_grid: mdl values tried when tuning, square metres.
        threshold: matching threshold of the tuning objective, e.g. ``"2/3"`` or ``"1"``.

    Attributes:
        stride_: the stride used, metres (tuned or given).
        mdl_: the mdl used, square metres (tuned or given).
        grid_search_: the :class:`GridSearch` when tuned, else None.
    """

    def __init__(
        self,
        *,
        stride: float = STRIDE_M,
        mdl: float = MDL_M2,
        orientation: str = "body",
        tune: bool = False,
        stride_grid: Sequence[float] = STRIDE_GRID_M,
        mdl_grid: Sequence[float] = MDL_GRID_M2,
        threshold: str = "2/3",
    ) -> None:
        self.stride = stride
        self.mdl = mdl
        self.orientation = orientation
        self.tune = tune
        self.stride_grid = stride_grid
        self.mdl_grid = mdl_grid
        self.threshold = threshold

    @classmethod
    def from_settings(cls, *, stride: float, mdl: float, units: str = "cm", **kwargs: Any) -> Gcff:
        """A detector from settings in another unit, e.g. a ``settings_gc.mat`` in centimetres.

        ``Gcff.from_settings(stride=70, mdl=10000, units="cm")`` equals
        ``Gcff(stride=0.7, mdl=1.0)``.
        """
        metres = _centimetres_per(units) / CM_PER_M  # metres per unit
        return cls(stride=_convert(stride, metres), mdl=_convert(mdl, metres * metres), **kwargs)

    @classmethod
    def from_settings_file(
        cls, path: str | os.PathLike[str], *, units: str = "cm", **kwargs: Any
    ) -> Gcff:
        """A detector from a GCFF ``settings_gc.mat`` (variables ``stride`` and ``mdl``).

        Args:
            path: the ``.mat`` file.
            units: length unit of the file's values: ``"cm"`` (as the published ones) or ``"m"``.
            **kwargs: other parameters (``orientation``).

        Raises:
            ValueError: ``units`` is unknown.
            DataFormatError: the file is missing or unreadable, or ``stride`` / ``mdl`` is
                missing, not a numeric scalar, or out of range (``stride >= 0``, ``mdl > 0``,
                at most :data:`STRIDE_LIMIT_M` and :data:`MDL_LIMIT_M2` in ``units``).
        """
        from reform.datasets.gcff_mat import read_settings

        _centimetres_per(units)  # an unknown unit is named before the file is read
        values = read_settings(Path(path), units=units)
        return cls.from_settings(stride=values["stride"], mdl=values["mdl"], units=units, **kwargs)

    def _validate(self) -> None:
        _check_positive("stride", self.stride, allow_zero=True)
        _check_positive("mdl", self.mdl)
        if self.orientation not in ORIENTATIONS:
            raise ValueError(f"orientation must be one of {ORIENTATIONS}, got {self.orientation!r}")

    max_frame_bytes = MAX_FRAME_BYTES  # the most it takes on one frame (larger are refused)

    def frame_bytes(self, n_people: int) -> int:
        """Bytes it takes at its peak on one frame of ``n_people`` (:func:`frame_bytes`, at the
        largest mdl it may use)."""
        return frame_bytes(n_people, mdl=max(self.mdl_grid) if self.tune else self.mdl)

    def fit(self, frames: Sequence[Frame]) -> Gcff:
        """Validates the parameters; with ``tune=True``, picks stride and mdl on ``frames``."""
        self._validate()
        frames = check_frames(frames)
        if self.tune:
            search = grid_search(
                frames,
                stride_grid=self.stride_grid,
                mdl_grid=self.mdl_grid,
                orientation=self.orientation,
                threshold=self.threshold,
            )
            self.stride_, self.mdl_, self.grid_search_ = (
                search.best_stride,
                search.best_mdl,
                search,
            )
        else:
            self.stride_, self.mdl_, self.grid_search_ = float(self.stride), float(self.mdl), None
        return self

    def _settings(self) -> tuple[float, float]:
        if self.tune:
            if not hasattr(self, "stride_"):
                raise not_fitted_error(
                    "Gcff(tune=True) must be fitted on training frames before predict; "
                    "call fit(frames) first, or use tune=False with explicit stride and mdl"
                )
            return self.stride_, self.mdl_
        self._validate()
        return float(self.stride), float(self.mdl)

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One full partition per frame: groups in order of first member, singletons included."""
        stride, mdl = self._settings()
        return _predict(check_frames(frames), stride=stride, mdl=mdl, orientation=self.orientation)

    def predict_labels(self, frame: Frame) -> np.ndarray:
        """(n,) int64 GCFF labels of one frame (row order of ``frame.ids``)."""
        stride, mdl = self._settings()
        return gcff_labels(
            frame.position, _orientation(frame, self.orientation), stride=stride, mdl=mdl
        )

    def __sklearn_is_fitted__(self) -> bool:
        return not self.tune or hasattr(self, "stride_")


class GcffBySequence(Estimator):
    """GCFF with each sequence's own settings: the field's per-dataset protocol.

    The GCFF authors tuned ``stride`` and ``mdl`` for every dataset and shipped them beside it
    (``settings_gc.mat``, one per sequence in CoffeeBreak and GDet). This detector runs
    :class:`Gcff` on every frame with the settings of the frame's ``sequence``.

    Args:
        settings: sequence name -> ``(stride, mdl)`` in metres and square metres.
        orientation: as :class:`Gcff`.
    """

    def __init__(
        self, *, settings: Mapping[str, tuple[float, float]], orientation: str = "body"
    ) -> None:
        self.settings = settings
        self.orientation = orientation

    @classmethod
    def from_dataset(cls, dataset: Any, **kwargs: Any) -> GcffBySequence:
        """The settings a loaded GCFF dataset ships (``metadata["settings_gc_by_sequence"]``).

        Raises:
            ValueError: a sequence of the dataset ships no settings (naming it).
        """
        shipped = dict(dataset.metadata.get("settings_gc_by_sequence") or {})
        settings = {}
        for sequence in dataset.sequences():
            entry = shipped.get(sequence)
            if not entry or "stride_m" not in entry or "mdl_m2" not in entry:
                raise ValueError(
                    f"dataset {dataset.name!r}: sequence {sequence!r} ships no GCFF settings "
                    "(settings_gc.mat with stride and mdl)"
                )
            settings[sequence] = (float(entry["stride_m"]), float(entry["mdl_m2"]))
        return cls(settings=settings, **kwargs)

    max_frame_bytes = MAX_FRAME_BYTES  # the most it takes on one frame (larger are refused)

    def frame_bytes(self, n_people: int) -> int:
        """Bytes it takes at its peak on one frame of ``n_people`` (:func:`frame_bytes`, at the
        largest mdl of its sequences)."""
        return frame_bytes(
            n_people, mdl=max((m for _, m in dict(self.settings).values()), default=MDL_M2)
        )

    def fit(self, frames: Sequence[Frame]) -> GcffBySequence:
        """Nothing to learn: validates the settings."""
        self._detectors()
        check_frames(frames)
        return self

    def _detectors(self) -> dict[str, Gcff]:
        detectors = {}
        for sequence, (stride, mdl) in dict(self.settings).items():
            detector = Gcff(stride=stride, mdl=mdl, orientation=self.orientation)
            detector._validate()
            detectors[str(sequence)] = detector
        return detectors

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One full partition per frame, each with its sequence's settings.

        Raises:
            ValueError: a frame's sequence has no settings.
        """
        frames = check_frames(frames)
        detectors = self._detectors()
        out: list[tuple[Group, ...] | None] = [None] * len(frames)
        by_sequence: dict[str, list[int]] = {}
        for k, frame in enumerate(frames):
            by_sequence.setdefault(frame.sequence, []).append(k)
        for sequence, rows in by_sequence.items():
            if sequence not in detectors:
                raise ValueError(
                    f"frames[{rows[0]}] is of sequence {sequence!r}, which has no GCFF settings "
                    f"(settings for {sorted(detectors)})"
                )
            for k, partition in zip(
                rows, detectors[sequence].predict([frames[k] for k in rows]), strict=True
            ):
                out[k] = partition
        return out  # type: ignore[return-value]

    def __sklearn_is_fitted__(self) -> bool:
        return True


class GcffOwn(Estimator):
    """GCFF with the settings the dataset it runs on ships: the catalogue's ``gcff-own``.

    Made without a dataset, it is specialised to one by :meth:`for_dataset` (the commands that
    score a dataset do it): :class:`GcffBySequence` with each sequence's ``settings_gc.mat``.

    Args:
        orientation: as :class:`Gcff`.
    """

    def __init__(self, *, orientation: str = "body") -> None:
        self.orientation = orientation

    def for_dataset(self, dataset: Any) -> GcffBySequence:
        """GCFF with the settings ``dataset`` ships, per sequence.

        Raises:
            ValueError: a sequence of the dataset ships no settings (naming it).
        """
        return GcffBySequence.from_dataset(dataset, orientation=self.orientation)

    def fit(self, frames: Sequence[Frame]) -> GcffOwn:
        """Nothing to learn."""
        check_frames(frames)
        return self

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """Refused: the settings come from a dataset (:meth:`for_dataset`)."""
        raise ValueError(
            "gcff-own runs with the settings a dataset ships: specialise it with "
            "for_dataset(dataset) (reform-sim evaluate, detect and benchmark do)"
        )

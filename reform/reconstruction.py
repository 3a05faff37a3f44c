"""Reconstruction: from pairwise predictions (the Relation Matrix) back to F-formations.

**Greedy Reconstruction** (the paper's Algorithm 1, read as its prose says): ``B_i`` is the set
of people that row ``i`` of the Relation Matrix marks 1. While at least two of the remaining
people are predicted together, take the pair ``(i, j)`` with ``M[i, j] = 1`` whose beliefs agree
most, the largest ``|B_i ∩ B_j|`` (both sets restricted to the remaining people; ties go to the
lowest ``(i, j)``), emit ``B_i ∪ B_j`` (remaining people only) as an F-formation and remove its
members. Everyone left over is a singleton. The ``"intersection"`` variant emits
``(B_i ∩ B_j) ∪ {i, j}`` instead.

Two implementations give the same partitions:

* :func:`greedy_reconstruction` follows the definition step by step on one matrix; it is the
  reference, and it accepts any square boolean matrix (rows are read as the beliefs, so the
  paper's worked example, whose belief sets are not symmetric, can be written down as given).
* :func:`batch_greedy_labels` reconstructs many frames at once from their pair labels, with the
  beliefs as bitsets. Two facts make it fast: a connected component of the predicted graph in
  which every member holds the same beliefs is a clique and comes out as one group, whatever the
  order; and the greedy loop never mixes components, so only the people of inconsistent
  components go through the loop, all frames in lock-step.

**Correlation clustering** (``"correlation"``, an option beyond the paper) uses the classifier's
pair probabilities rather than its hard votes. Each pair gets the weight
``w_ij = logit(p_ij) - logit(t)`` (:func:`pair_weights`; ``t`` the detector's threshold, 0.5 by
default, so a pair at probability ``t`` weighs nothing, a likely pair pulls its members together
and an unlikely one pushes them apart, each in proportion to the classifier's confidence), and
the partition sought maximises the summed weight of the pairs it puts together
(:func:`correlation_clustering`). Finding the best partition is NP-hard; the heuristic here is
deterministic, on each connected component of the pairs of positive weight (no group joining two
components can score higher): greedy agglomeration (start from singletons, repeatedly merge the
two groups whose summed cross weight is the largest positive one, ties to the lowest pair of
groups), then local moves (each person in row order may move to the group, or to a group of
their own, that raises the total most; passes repeat until none does). Unlike Greedy
Reconstruction, a pair the classifier gives 0.51 and one it gives 0.99 count differently, and
one confident "apart" can keep two otherwise linked people out of one group.

The weight: log-odds, rather than ``p - t``, because the sum of the pairs' log-odds over a
partition is, up to a constant, the log-likelihood of that partition if the pair probabilities
were independent and calibrated; the data did not decide between the two (SALSA's training
split, time-blocked cross-validation, ``sim.experiments.reform_options``: group F1 at T = 2/3
0.781 with log-odds and 0.786 with ``p - 0.5`` at the recorded scale, 0.733 and 0.724 with
positions scaled by 0.6, equal at 1.6).

Partitions are canonical: groups ordered by their first member, members in row order,
singletons included.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from reform.features import pair_indices

UNION = "union"
INTERSECTION = "intersection"
CORRELATION = "correlation"
GREEDY_VARIANTS = (UNION, INTERSECTION)  # reconstructions from hard pair labels
RECONSTRUCTIONS = (UNION, INTERSECTION, CORRELATION)
PROBABILITY_CLIP = 1e-3  # pair probabilities are clipped to [this, 1 - this] before the
# log-odds, so that a pair of probability 0 or 1 weighs about 6.9 rather than infinitely much
MOVE_TOLERANCE = 1e-9  # a local move must raise the total weight by more than this

__all__ = [
    "CORRELATION",
    "GREEDY_VARIANTS",
    "INTERSECTION",
    "PROBABILITY_CLIP",
    "RECONSTRUCTIONS",
    "UNION",
    "batch_correlation_labels",
    "batch_greedy_labels",
    "check_reconstruction",
    "correlation_clustering",
    "graph_greedy_labels",
    "greedy_reconstruction",
    "pair_weights",
    "partition_from_labels",
    "relation_matrix",
]


def check_reconstruction(variant: str, allowed: Sequence[str] = RECONSTRUCTIONS) -> str:
    """Validates a reconstruction name against ``allowed``."""
    if not isinstance(variant, str) or variant not in allowed:
        raise ValueError(f"reconstruction must be one of {tuple(allowed)}, got {variant!r}")
    return variant


def pair_weights(probability: npt.ArrayLike, *, threshold: float | None = None) -> np.ndarray:
    """Correlation-clustering weights of pairs: ``logit(p) - logit(t)``.

    Args:
        probability: (...) pair probabilities of being together, clipped to
            ``[PROBABILITY_CLIP, 1 - PROBABILITY_CLIP]``.
        threshold: the probability ``t`` that weighs nothing; None for 0.5.

    Returns:
        (...) float64 weights: positive pulls the pair together, negative pushes it apart.
    """
    p = np.clip(np.asarray(probability, dtype=np.float64), PROBABILITY_CLIP, 1 - PROBABILITY_CLIP)
    weight = np.log(p) - np.log1p(-p)
    if threshold is not None:
        weight -= math.log(threshold) - math.log1p(-threshold)
    return weight


def correlation_clustering(weights: npt.ArrayLike) -> np.ndarray:
    """Correlation clustering of one frame: agglomeration, then local moves (module notes).

    The connected components of the pairs of positive weight are clustered one by one: a
    group that spans two components holds only pairs of weight <= 0 across them, so splitting
    it never lowers the total, and a person without a positive pair stays alone.

    Args:
        weights: (n, n) symmetric pair weights (the diagonal is ignored).

    Returns:
        (n,) intp group labels, each person's the row of their group's first member.
    """
    w = np.array(weights, dtype=np.float64)
    if w.ndim != 2 or w.shape[0] != w.shape[1]:
        raise ValueError(f"weights must be a square (n, n) matrix, got shape {w.shape}")
    if not np.all(np.isfinite(w)):
        raise ValueError("weights must be finite")
    n = w.shape[0]
    np.fill_diagonal(w, 0.0)
    labels = np.arange(n, dtype=np.intp)
    if n < 2:
        return labels
    component = _components(w > 0)
    for c in np.unique(component):
        rows = np.flatnonzero(component == c)  # ascending: the component's own row order
        if rows.size == 2:
            labels[rows[1]] = rows[0]  # one positive pair: together
        elif rows.size > 2:
            labels[rows] = rows[_cluster(w[np.ix_(rows, rows)])]
    return labels


def _components(adjacent: np.ndarray) -> np.ndarray:
    """(n,) each row's connected component of an (n, n) symmetric bool adjacency, named by its
    lowest row (labels spread to neighbours until none changes: as many steps as the widest
    component is long, each one numpy call; for a frame, cheaper than a sparse graph)."""
    n = adjacent.shape[0]
    labels = np.arange(n, dtype=np.intp)
    while True:
        spread = np.where(adjacent, labels[None, :], n).min(axis=1)
        np.minimum(spread, labels, out=spread)
        if np.array_equal(spread, labels):
            return labels
        labels = spread


def _cluster(w: np.ndarray) -> np.ndarray:
    """Agglomeration then local moves on one component: (n,) labels, each a member row."""
    n = w.shape[0]
    labels = np.arange(n, dtype=np.intp)
    # Agglomeration: cluster-to-cluster summed weights, clusters named by a member row.
    between = w.copy()
    alive = np.ones(n, dtype=bool)
    upper = np.triu(np.ones((n, n), dtype=bool), k=1)
    while True:
        gain = np.where(upper & alive[:, None] & alive[None, :], between, -np.inf)
        a, b = divmod(int(np.argmax(gain)), n)  # first maximum: lowest (a, b)
        if not gain[a, b] > 0:
            break
        between[a] += between[b]
        between[:, a] += between[:, b]
        alive[b] = False
        labels[labels == b] = a
    # Local moves: support[v, c] = summed weight of v to the members of cluster c.
    member = labels[:, None] == np.arange(n)[None, :]
    support = w @ member
    counts = member.sum(axis=0)
    moved = True
    while moved:  # the total weight rises by > MOVE_TOLERANCE each move: this ends
        moved = False
        for v in range(n):
            c = labels[v]
            own = support[v, c]
            options = np.where(counts > 0, support[v], -np.inf)
            options[c] = -np.inf
            d = int(np.argmax(options))
            best = options[d] - own
            alone = -own if counts[c] > 1 else -np.inf
            if alone > best:
                d, best = int(np.flatnonzero(counts == 0)[0]), alone
            if best > MOVE_TOLERANCE:
                support[:, c] -= w[:, v]
                support[:, d] += w[:, v]
                counts[c] -= 1
                counts[d] += 1
                labels[v] = d
                moved = True
    # Canonical labels: the first member's row.
    first = np.full(n, n, dtype=np.intp)
    np.minimum.at(first, labels, np.arange(n, dtype=np.intp))
    return first[labels]


def batch_correlation_labels(
    probabilities: npt.ArrayLike, n: int, *, threshold: float | None = None
) -> np.ndarray:
    """Correlation clustering of many frames of ``n`` people from their pair probabilities.

    Args:
        probabilities: (F, n(n-1)/2) pair probabilities, pairs in
            :func:`reform.features.pair_indices` order.
        n: number of people in every frame.
        threshold: the probability that weighs nothing (:func:`pair_weights`); None for 0.5.

    Returns:
        (F, n) intp group labels, as :func:`batch_greedy_labels` gives them.
    """
    weights = pair_weights(probabilities, threshold=threshold)
    i, j = pair_indices(n)
    if weights.ndim != 2 or weights.shape[1] != i.size:
        raise ValueError(
            f"probabilities must have shape (frames, {i.size}) for n={n}, got {weights.shape}"
        )
    out = np.broadcast_to(np.arange(n, dtype=np.intp), (weights.shape[0], n)).copy()
    if n < 2:
        return out
    matrix = np.zeros((n, n))
    for f, row in enumerate(weights):
        if not (row > 0).any():  # nobody pulls: everyone alone
            continue
        matrix[i, j] = row
        matrix[j, i] = row
        out[f] = correlation_clustering(matrix)
    return out


def relation_matrix(pair_labels: npt.ArrayLike, n: int) -> np.ndarray:
    """The Relation Matrix ``M_R`` of one frame from its pair labels.

    Args:
        pair_labels: (n(n-1)/2,) predicted labels (truthy = together), pairs in
            :func:`reform.features.pair_indices` order.
        n: number of people.

    Returns:
        (n, n) bool, symmetric, diagonal True.
    """
    labels = np.asarray(pair_labels).astype(bool, copy=False)
    i, j = pair_indices(n)
    if labels.shape != i.shape:
        raise ValueError(f"pair_labels must have shape ({i.size},) for n={n}, got {labels.shape}")
    matrix = np.eye(n, dtype=bool)
    matrix[i, j] = labels
    matrix[j, i] = labels
    return matrix


def greedy_reconstruction(
    relation: npt.ArrayLike, *, variant: str = UNION
) -> tuple[tuple[int, ...], ...]:
    """Greedy Reconstruction of one Relation Matrix (the reference implementation).

    Args:
        relation: (n, n) boolean matrix; row ``i`` is the belief set ``B_i``. A pair ``(i, j)``
            is a candidate when ``relation[i, j]`` or ``relation[j, i]`` is set. Relation
            Matrices from a classifier are symmetric with a True diagonal.
        variant: ``"union"`` (the paper's prose, default) or ``"intersection"``.

    Returns:
        The partition of the rows ``0..n-1``: groups ordered by their first member, members
        ascending, singletons included.
    """
    check_reconstruction(variant, GREEDY_VARIANTS)
    matrix = np.asarray(relation)
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1]:
        raise ValueError(f"relation must be a square (n, n) matrix, got shape {matrix.shape}")
    matrix = matrix.astype(bool)
    n = matrix.shape[0]
    candidate = np.triu(matrix | matrix.T, k=1)
    remaining = np.ones(n, dtype=bool)
    group_of = np.arange(n)
    while True:
        live = candidate & remaining[:, None] & remaining[None, :]
        if not live.any():
            break
        beliefs = (matrix & remaining[None, :]).astype(np.int64)
        agreement = beliefs @ beliefs.T  # |B_i ∩ B_j| over the remaining people
        score = np.where(live, agreement, -1)
        i, j = divmod(int(np.argmax(score)), n)  # first maximum in row-major order: lowest (i, j)
        if variant == UNION:
            members = (matrix[i] | matrix[j]) & remaining
        else:
            members = matrix[i] & matrix[j] & remaining
            members[[i, j]] = True
        rows = np.flatnonzero(members)
        group_of[rows] = rows[0]
        remaining &= ~members
    return partition_from_labels(group_of, range(n))


def partition_from_labels(
    labels: npt.ArrayLike, ids: Sequence[int] | np.ndarray
) -> tuple[tuple[int, ...], ...]:
    """A partition from group labels: people with the same label form a group.

    Args:
        labels: (n,) labels; the canonical label of a group is its first member's row.
        ids: (n,) the people's ids.

    Returns:
        Groups of ids in order of first appearance, members in row order, singletons included.
    """
    groups: dict[int, list[int]] = {}
    for label, person in zip(np.asarray(labels).tolist(), list(ids), strict=True):
        groups.setdefault(label, []).append(int(person))
    return tuple(tuple(members) for members in groups.values())


def _pack(mask: np.ndarray) -> np.ndarray:
    """(..., n) bool -> (..., W) uint64 bitsets, W = ceil(n / 64), element k = bit k overall."""
    n = mask.shape[-1]
    words = max(1, -(-n // 64))
    packed = np.packbits(mask, axis=-1, bitorder="little")
    padding = words * 8 - packed.shape[-1]
    if padding:
        pad = np.zeros(packed.shape[:-1] + (padding,), dtype=np.uint8)
        packed = np.concatenate([packed, pad], axis=-1)
    return np.ascontiguousarray(packed).view("<u8")


def _unpack(bits: np.ndarray, n: int) -> np.ndarray:
    """Inverse of :func:`_pack`: (..., W) uint64 -> (..., n) bool."""
    as_bytes = np.ascontiguousarray(bits).view(np.uint8)
    return np.unpackbits(as_bytes, axis=-1, count=n, bitorder="little").view(bool)


_SMALL_BATCH = 4  # frames: below this, plain Python integers beat array operations


def _beliefs(pair_labels: np.ndarray, n: int) -> np.ndarray:
    """(F, P) bool pair labels -> (F, n, W) uint64 belief bitsets, each including its own bit."""
    i, j = pair_indices(n)
    matrix = np.zeros((pair_labels.shape[0], n * n), dtype=bool)
    matrix[:, i * n + j] = pair_labels
    matrix[:, j * n + i] = pair_labels
    matrix[:, np.arange(n) * (n + 1)] = True
    return _pack(matrix.reshape(-1, n, n))


def _lowest_bit(bits: np.ndarray) -> np.ndarray:
    """(..., W) uint64 bitsets (none empty) -> (...) index of their lowest set bit."""
    words = bits.shape[-1]
    first_word = (
        np.argmax(bits != 0, axis=-1) if words > 1 else np.zeros(bits.shape[:-1], dtype=np.intp)
    )
    word = np.take_along_axis(bits, first_word[..., None], axis=-1)[..., 0]
    low = word & (~word + np.uint64(1))
    return (np.bitwise_count(low - np.uint64(1)).astype(np.intp) + 64 * first_word).astype(np.intp)


def batch_greedy_labels(pair_labels: npt.ArrayLike, n: int, *, variant: str = UNION) -> np.ndarray:
    """Greedy Reconstruction of many frames of ``n`` people at once.

    Args:
        pair_labels: (F, n(n-1)/2) predicted pair labels (truthy = together), pairs in
            :func:`reform.features.pair_indices` order.
        n: number of people in every frame.
        variant: ``"union"`` or ``"intersection"``.

    Returns:
        (F, n) intp group labels: each person's label is the row of the first member of their
        group (their own row for a singleton). Same partitions as :func:`greedy_reconstruction`
        on each frame's Relation Matrix.
    """
    check_reconstruction(variant, GREEDY_VARIANTS)
    labels_in = np.asarray(pair_labels).astype(bool, copy=False)
    i, j = pair_indices(n)
    if labels_in.ndim != 2 or labels_in.shape[1] != i.size:
        raise ValueError(
            f"pair_labels must have shape (frames, {i.size}) for n={n}, got {labels_in.shape}"
        )
    n_frames = labels_in.shape[0]
    if n < 2 or n_frames == 0:
        return np.broadcast_to(np.arange(n, dtype=np.intp), (n_frames, n)).copy()
    if n_frames < _SMALL_BATCH and n <= 64:
        return np.array([_greedy_python(row, n, variant) for row in labels_in], dtype=np.intp)
    if n > _WORD_PEOPLE:  # the frames as one graph of n_frames * n people, its pairs listed
        frame_of, pair = np.nonzero(labels_in)
        offset = frame_of * n
        labels = graph_greedy_labels(
            n_frames * n, offset + i[pair], offset + j[pair], variant=variant
        )
        return (labels - np.repeat(np.arange(n_frames) * n, n)).reshape(n_frames, n)

    beliefs = _beliefs(labels_in, n)[..., 0]  # (F, n): up to 64 people, one word each
    # A consistent person's group is their belief set; its first member is the label.
    out = _lowest_bit(beliefs[..., None])
    conflict = labels_in & (np.take(beliefs, i, axis=1) != np.take(beliefs, j, axis=1))
    if not conflict.any():
        return out
    frame_of, pair = np.nonzero(conflict)
    loose = np.zeros((n_frames, n), dtype=bool)  # people of inconsistent components
    loose[frame_of, i[pair]] = True
    loose[frame_of, j[pair]] = True
    frames = np.flatnonzero(loose.any(axis=1))
    _greedy_loop_word(labels_in[frames], beliefs[frames], loose[frames], out, frames, n, variant)
    return out


def _greedy_loop_word(
    pair_labels: np.ndarray,
    beliefs: np.ndarray,
    loose: np.ndarray,
    out: np.ndarray,
    frames: np.ndarray,
    n: int,
    variant: str,
) -> None:
    """The greedy loop for up to 64 people, beliefs as one uint64 word, writing into ``out``.

    Only candidate pairs (predicted together, both in an inconsistent component) are kept, packed
    to the left of a (frames, C) array in pair order, so the first maximum is still the lowest
    pair; the groups are collected as bitsets and written out once at the end.
    """
    i, j = pair_indices(n)
    one = np.uint64(1)
    local = np.arange(frames.size)
    out[frames] = np.where(loose, np.arange(n, dtype=np.intp), out[frames])
    candidate = pair_labels & loose[:, i] & loose[:, j]
    counts = candidate.sum(axis=1)
    width = int(counts.max())
    rows, pairs = np.nonzero(candidate)  # row-major: each frame's candidates in pair order
    row_start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.arange(rows.size) - row_start[rows]
    first = np.zeros((frames.size, width), dtype=np.uint64)
    second = np.zeros((frames.size, width), dtype=np.uint64)
    first[rows, slot] = i[pairs]
    second[rows, slot] = j[pairs]
    valid = np.arange(width) < counts[:, None]
    flat = beliefs.ravel()
    row_base = (local * n)[:, None]
    common = flat[row_base + first.astype(np.intp)] & flat[row_base + second.astype(np.intp)]
    remaining = _pack(loose)[:, 0]
    bit_first = one << first
    bit_second = one << second
    emitted_frames, emitted_bits = [], []
    active = local
    while active.size:
        rem = remaining[active][:, None]
        live = valid[active] & ((rem & bit_first[active]) != 0) & ((rem & bit_second[active]) != 0)
        agreement = np.bitwise_count(common[active] & rem).astype(np.int8)
        score = np.where(live, agreement, np.int8(-1))
        best = np.argmax(score, axis=1)  # first maximum: lowest (i, j)
        keep = np.take_along_axis(score, best[:, None], axis=1)[:, 0] >= 0
        if not keep.all():
            active, best, rem = active[keep], best[keep], rem[keep]
            if active.size == 0:
                break
        a = np.take_along_axis(first[active], best[:, None], axis=1)[:, 0]
        b = np.take_along_axis(second[active], best[:, None], axis=1)[:, 0]
        belief_a = flat[active * n + a.astype(np.intp)]
        belief_b = flat[active * n + b.astype(np.intp)]
        if variant == UNION:
            members = (belief_a | belief_b) & rem[:, 0]
        else:
            members = (belief_a & belief_b & rem[:, 0]) | (one << a) | (one << b)
        emitted_frames.append(active)
        emitted_bits.append(members)
        remaining[active] = rem[:, 0] & ~members
    if not emitted_frames:
        return
    group_frames = np.concatenate(emitted_frames)
    group_bits = np.concatenate(emitted_bits)
    leader = _lowest_bit(group_bits[:, None])
    members = _unpack(group_bits[:, None], n)
    g, person = np.nonzero(members)
    out[frames[group_frames[g]], person] = leader[g]


def _greedy_python(pair_labels: np.ndarray, n: int, variant: str) -> list[int]:
    """One frame with Python integers as bitsets: fastest for a single small frame."""
    i, j = pair_indices(n)
    hits = np.flatnonzero(pair_labels).tolist()
    first = i.tolist()
    second = j.tolist()
    beliefs = [1 << k for k in range(n)]
    pairs = []
    for p in hits:
        a, b = first[p], second[p]
        beliefs[a] |= 1 << b
        beliefs[b] |= 1 << a
        pairs.append((a, b))
    labels = [(bits & -bits).bit_length() - 1 for bits in beliefs]
    loose = 0
    for a, b in pairs:
        if beliefs[a] != beliefs[b]:
            loose |= (1 << a) | (1 << b)
    if not loose:
        return labels
    # People of inconsistent components: their components are entirely loose.
    for k in range(n):
        if loose >> k & 1:
            labels[k] = k
    remaining = loose
    candidates = [(a, b) for a, b in pairs if loose >> a & 1]
    while True:
        best = -1
        pick = (0, 0)
        for a, b in candidates:  # in (i, j) order: the first maximum is the lowest pair
            if remaining >> a & 1 and remaining >> b & 1:
                agreement = (beliefs[a] & beliefs[b] & remaining).bit_count()
                if agreement > best:
                    best = agreement
                    pick = (a, b)
        if best < 0:
            return labels
        a, b = pick
        if variant == UNION:
            members = (beliefs[a] | beliefs[b]) & remaining
        else:
            members = (beliefs[a] & beliefs[b] & remaining) | (1 << a) | (1 << b)
        leader = (members & -members).bit_length() - 1
        bits = members
        while bits:
            low = bits & -bits
            labels[low.bit_length() - 1] = leader
            bits ^= low
        remaining &= ~members


# --------------------------------------------------------------------------------------------
# Greedy Reconstruction one connected component at a time, from the pairs predicted together

_WORD_PEOPLE = 64  # components up to this many people hold each belief set in one uint64 word


def graph_greedy_labels(
    n: int, first: npt.ArrayLike, second: npt.ArrayLike, *, variant: str = UNION
) -> np.ndarray:
    """Greedy Reconstruction from the list of pairs predicted together, component by component.

    The greedy loop never mixes connected components of the predicted graph: a candidate pair
    lies inside one, its beliefs ``B_i``, ``B_j`` and so its agreement and its emitted group lie
    inside it too, and removing a group changes no other component's agreements. A
    component's own sequence of choices is therefore the one the whole-matrix loop makes, and
    each is reconstructed on its own: a component in which everyone is predicted together with
    everyone (a clique) is one group; the others go through the loop, those of up to 64 people
    all at once with each belief set in one machine word, larger ones one by one with their
    agreements updated only near the group just emitted. Memory grows with the number of people
    and of pairs predicted together, not with the square of the people.

    Args:
        n: number of people (rows ``0..n-1``).
        first: (E,) the lower row of each pair predicted together.
        second: (E,) the higher row of each pair (``first < second``); pairs in any order,
            repeats allowed.
        variant: ``"union"`` or ``"intersection"``.

    Returns:
        (n,) intp group labels, each person's the row of their group's first member, as
        :func:`batch_greedy_labels` gives them; the same partition as
        :func:`greedy_reconstruction` on the Relation Matrix of these pairs.
    """
    check_reconstruction(variant, GREEDY_VARIANTS)
    n = int(n)
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    a = np.asarray(first).astype(np.int64, copy=False).ravel()
    b = np.asarray(second).astype(np.int64, copy=False).ravel()
    if a.shape != b.shape:
        raise ValueError(f"first and second must have one shape, got {a.shape} and {b.shape}")
    if a.size and not (np.all(a < b) and a.min() >= 0 and b.max() < n):
        raise ValueError(f"pairs must satisfy 0 <= first < second < n={n}")
    out = np.arange(n, dtype=np.intp)
    if a.size == 0:
        return out
    key = np.unique(a * n + b)  # sorted: pairs in (first, second) order, the tie-break order
    a, b = np.divmod(key, n)
    # SciPy here: `train --help` lists RECONSTRUCTIONS without loading it
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components

    count, component = connected_components(
        coo_array((np.ones(a.size, dtype=np.int8), (a, b)), shape=(n, n)), directed=False
    )
    _, leader = np.unique(component, return_index=True)  # each component's first member
    out[:] = leader[component]
    size = np.bincount(component, minlength=count)
    pairs = np.bincount(component[a], minlength=count)
    loose = pairs < size * (size - 1) // 2  # not a clique: the greedy loop decides
    if not loose.any():
        return out
    edge_loose = loose[component[a]]
    a, b = a[edge_loose], b[edge_loose]
    people = np.flatnonzero(loose[component])  # ascending
    out[people] = people
    order = np.argsort(component[people], kind="stable")  # by component, rows ascending inside
    people = people[order]
    comp_of = component[people]
    starts = np.flatnonzero(np.r_[True, comp_of[1:] != comp_of[:-1]])
    local = np.empty(n, dtype=np.int64)  # each loose person's place in their component
    local[people] = np.arange(people.size) - np.repeat(starts, np.diff(np.r_[starts, people.size]))
    small = size[comp_of[starts]] <= _WORD_PEOPLE
    edge_order = np.argsort(component[a], kind="stable")  # by component, pair order inside
    a, b = a[edge_order], b[edge_order]
    edge_comp = component[a]
    small_comp = np.zeros(count, dtype=bool)
    small_comp[comp_of[starts[small]]] = True
    on_word = small_comp[edge_comp]
    if on_word.any():
        _word_components(a[on_word], b[on_word], edge_comp[on_word], local, out, variant)
    for start in starts[~small].tolist():
        c = component[people[start]]
        inside = edge_comp == c
        members = people[start : start + size[c]]
        _large_component(members, local[a[inside]], local[b[inside]], out, variant)
    return out


def _word_components(
    a: np.ndarray,
    b: np.ndarray,
    edge_comp: np.ndarray,
    local: np.ndarray,
    out: np.ndarray,
    variant: str,
) -> None:
    """The greedy loop over components of at most 64 people, all in lock-step, writing into
    ``out``. ``a``, ``b``: (E,) rows of their pairs, grouped by component ``edge_comp`` and in
    pair order inside; ``local``: each person's place in their component."""
    one = np.uint64(1)
    la = local[a].astype(np.uint64)
    lb = local[b].astype(np.uint64)
    bit_a = one << la
    bit_b = one << lb
    # Belief words over local places, per person (a person's own bit included).
    people = np.unique(np.concatenate([a, b]))
    slot = np.searchsorted(people, a), np.searchsorted(people, b)
    word = one << local[people].astype(np.uint64)
    np.bitwise_or.at(word, slot[0], bit_b)
    np.bitwise_or.at(word, slot[1], bit_a)
    word_a, word_b = word[slot[0]], word[slot[1]]
    common = word_a & word_b
    comps, edge_comp = np.unique(edge_comp, return_inverse=True)
    remaining = np.full(
        comps.size, np.iinfo(np.uint64).max, dtype=np.uint64
    )  # bits of each component's people not yet in a group
    row_of = np.zeros((comps.size, _WORD_PEOPLE), dtype=np.int64)  # local place -> row
    row_of[edge_comp, la.astype(np.intp)] = a
    row_of[edge_comp, lb.astype(np.intp)] = b
    emitted_comp, emitted_bits = [], []
    edge = np.arange(a.size)
    while edge.size:
        c = edge_comp[edge]
        rem = remaining[c]
        live = ((rem & bit_a[edge]) != 0) & ((rem & bit_b[edge]) != 0)
        edge, c, rem = edge[live], c[live], rem[live]
        if edge.size == 0:
            break
        score = np.bitwise_count(common[edge] & rem).astype(np.int16)
        opens = np.flatnonzero(np.r_[True, c[1:] != c[:-1]])
        best = np.maximum.reduceat(score, opens)
        at_best = np.where(score == np.repeat(best, np.diff(np.r_[opens, c.size])), edge, a.size)
        pick = np.minimum.reduceat(at_best, opens)  # first maximum: the lowest pair
        chosen = c[opens]
        rem_c = remaining[chosen]
        if variant == UNION:
            members = (word_a[pick] | word_b[pick]) & rem_c
        else:
            members = (common[pick] & rem_c) | bit_a[pick] | bit_b[pick]
        remaining[chosen] = rem_c & ~members
        emitted_comp.append(chosen)
        emitted_bits.append(members)
    if not emitted_comp:
        return
    group_comp = np.concatenate(emitted_comp)
    group_bits = np.concatenate(emitted_bits)
    member = _unpack(group_bits[:, None], _WORD_PEOPLE)  # (groups, 64)
    g, place = np.nonzero(member)
    rows = row_of[group_comp[g], place]
    first_place = _lowest_bit(group_bits[:, None])
    out[rows] = row_of[group_comp, first_place][g]


_AGREEMENT_CHUNK = 1 << 16  # pairs whose agreement is counted at once in a large component


def _large_component(
    members: np.ndarray, a: np.ndarray, b: np.ndarray, out: np.ndarray, variant: str
) -> None:
    """The greedy loop over one component of more than 64 people, writing into ``out``.

    ``members``: (m,) its rows ascending; ``a``, ``b``: (E,) local places of its pairs, in pair
    order. Each pair's agreement is counted once and recounted only when a group containing a
    common neighbour of both members leaves.
    """
    m = members.size
    adjacent = np.zeros((m, m), dtype=bool)
    adjacent[a, b] = True
    adjacent[b, a] = True
    adjacent[np.arange(m), np.arange(m)] = True
    beliefs = _pack(adjacent)  # (m, W)
    del adjacent
    remaining = np.ones(m, dtype=bool)
    agreement = _agreement(beliefs, a, b, _pack(remaining))
    while a.size:
        k = int(np.argmax(agreement))  # pairs stay in pair order: the first is the lowest
        if variant == UNION:
            bits = (beliefs[a[k]] | beliefs[b[k]]) & _pack(remaining)
        else:
            bits = beliefs[a[k]] & beliefs[b[k]] & _pack(remaining)
        group = _unpack(bits, m)
        if variant != UNION:
            group[[a[k], b[k]]] = True
        rows = members[group]
        out[rows] = rows[0]
        remaining &= ~group
        near = np.zeros(m, dtype=bool)  # neighbours of the group: the only agreements it moves
        touch = group[a] | group[b]
        near[a[touch]] = True
        near[b[touch]] = True
        keep = remaining[a] & remaining[b]
        a, b, agreement = a[keep], b[keep], agreement[keep]
        stale = np.flatnonzero(near[a] & near[b])
        if stale.size:
            agreement[stale] = _agreement(beliefs, a[stale], b[stale], _pack(remaining))


def _agreement(
    beliefs: np.ndarray, a: np.ndarray, b: np.ndarray, remaining: np.ndarray
) -> np.ndarray:
    """(E,) ``|B_a ∩ B_b ∩ remaining|`` of pairs, counted a chunk of pairs at a time."""
    out = np.empty(a.size, dtype=np.int32)
    for start in range(0, a.size, _AGREEMENT_CHUNK):
        stop = start + _AGREEMENT_CHUNK
        both = beliefs[a[start:stop]] & beliefs[b[start:stop]] & remaining
        out[start:stop] = np.bitwise_count(both).sum(axis=-1, dtype=np.int32)
    return out

"""Dominant sets (Hung & Kröse, ICMI 2011): F-formations as the maximal cliques of a weighted graph.

People are the vertices of a graph whose edge weights ``A[i, j] >= 0`` say how much ``i`` and
``j`` look like members of one F-formation. A *dominant set* (Pavan & Pelillo, PAMI 2007) is a
subset whose members are more similar to each other than to anyone outside; its characteristic
vector is a strict local maximum of ``f(x) = x'Ax`` on the simplex, which the replicator
dynamics ``x_i <- x_i (Ax)_i / x'Ax`` reach from the simplex's centre. The groups are *peeled*
one at a time: find a dominant set of the people left, take it out, repeat.

**Stopping (the "global context" of Hung & Kröse).** A set found among the people left need not
be dominant among everyone: someone already taken, or someone left, may be more similar to it
than its members are to each other. Such a set is no F-formation, and peeling stops there: the
people not yet in a group are alone. For a set ``S`` with characteristic vector ``x`` (the
vector equalising the payoffs ``(A x)_k`` of its members), a person ``i`` outside breaks it when
``(A x)_i >= x'Ax``, which is the sign of Pavan & Pelillo's weight ``w_{S+i}(i)`` (a closed form
of the recursive weight the GTCG code computes). ``global_context=False`` peels to the end.

**The affinity of Hung & Kröse** (:func:`hung_krose_affinity`): a Gaussian of the distance,
``exp(-d² / 2σ²)``, kept only for pairs who each have the other in their field of view (the
direction to the other within ``field_of_view / 2`` of one's orientation), zero otherwise.

The replicator dynamics and the peeling (:func:`dominant_set_labels`) are shared with GTCG
(`reform.gtcg`), which feeds them its frustum affinities.

**Crowds: the whole frame at once.** Unlike HVFF's accumulator (`reform.hough`), the peeling
cannot be cut into parts of the frame that are peeled on their own with the same groups, for
three reasons, and so it runs on the whole frame at every size (its time grows about as n^3
on crowds: ``python benchmarks/bench_field_detectors.py --crowd``):

* the affinity is never zero between two people in each other's view closer than about 38.6
  sigma (62 m at the default sigma, where the Gaussian underflows), so in a crowd everyone is
  joined to everyone by chains of non-zero affinities;
* each set is the one the replicator dynamics reach from the centre of the simplex over
  *everyone left*, a race that the strongest set of the whole frame wins: the order in which
  sets are taken, and so who is still there when a neighbourhood is peeled, is the frame's;
* with ``global_context``, the first set that is not dominant stops the peeling for everyone,
  people far away included, who are all left alone. Even where the affinities split the frame
  into parts that share none, the parts' sets are (in exact arithmetic) the whole frame's, but
  whose non-dominant set comes first, and so which parts stop early, is decided by the race
  across them (``tests/reform/test_dominant_sets_crowd.py`` pins a far-away pair left alone
  so).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from reform._params import ORIENTATIONS, check_choice, check_number, orientation_of
from reform.estimator import Estimator
from reform.frame import Frame, Group, check_frames, wrap_angle
from reform.gcff import labels_to_partition

__all__ = [
    "FIELD_OF_VIEW_RAD",
    "RD_MAX_STEPS",
    "RD_TOL",
    "CELL_BYTES",
    "SIGMA_M",
    "SUPPORT",
    "DominantSets",
    "dominant_set_labels",
    "hung_krose_affinity",
    "replicator_dynamics",
]

# sigma and the field of view, which the paper leaves open, are chosen on SALSA's training split
# alone, by benchmarks/choose_field_defaults.py.
SIGMA_M = 1.6  # metres: the Gaussian's width
FIELD_OF_VIEW_RAD = 3.84  # radians (about 220°): the whole field of view
RD_TOL = 1e-9  # largest change of any share over 32 steps at which the dynamics have settled
RD_MAX_STEPS = 20_000  # steps of the replicator dynamics at most (the GTCG code: 3,000)
SUPPORT = 1e-5  # a share above SUPPORT * the largest share is in the set (the GTCG code's theta)
CELL_BYTES = 80  # bytes per (person, person) cell: the affinity and the replicator's working copies
_BLOCK = 32  # steps between convergence checks (a speed setting; results do not depend on it)
_PRUNE = 1e-14  # shares below _PRUNE * the largest are dropped for good while iterating
_DOMINANCE_TOL = 1e-9  # relative slack on (A x)_i >= x'Ax, against rounding


def replicator_dynamics(payoff: npt.ArrayLike) -> np.ndarray:
    """The replicator dynamics ``x_i <- x_i (Ax)_i / x'Ax`` run from the simplex's centre.

    Runs until no share changes by more than :data:`RD_TOL` over 32 steps (or
    :data:`RD_MAX_STEPS`). Shares that fall below ``1e-14`` of the largest are set to zero for
    good, which keeps the work on the few people who matter.

    Args:
        payoff: (n, n) symmetric non-negative matrix with a zero diagonal.

    Returns:
        (n,) float64 shares summing to 1 (the centre itself when every payoff is zero).
    """
    payoff = np.asarray(payoff, dtype=np.float64)
    n = payoff.shape[0]
    x = np.full(n, 1.0 / n) if n else np.zeros(0)
    active = np.arange(n)
    matrix = payoff
    steps = 0
    while steps < RD_MAX_STEPS and active.size > 1:
        before = x
        for _ in range(_BLOCK):
            ax = matrix @ x
            total = float(x @ ax)
            if total <= 0.0:  # no payoff anywhere: the centre is as good as any point
                out = np.zeros(n)
                out[active] = x
                return out
            x = x * ax / total
        steps += _BLOCK
        change = float(np.max(np.abs(x - before)))
        keep = x > _PRUNE * x.max()
        if not keep.all():
            x = x[keep] / x[keep].sum()
            matrix = matrix[np.ix_(keep, keep)]
            active = active[keep]
        if change < RD_TOL:
            break
    out = np.zeros(n)
    out[active] = x
    return out


def _characteristic_vector(block: np.ndarray, shares: np.ndarray) -> np.ndarray:
    """The shares over a set that equalise its members' payoffs (``block @ x`` constant, ``x``
    summing to 1), solved exactly; the replicator dynamics' shares when the system is singular
    or its solution leaves the simplex."""
    try:
        solved = np.linalg.solve(block, np.ones(block.shape[0]))
    except np.linalg.LinAlgError:
        return shares / shares.sum()
    if not np.all(np.isfinite(solved)) or solved.sum() <= 0 or np.any(solved <= 0):
        return shares / shares.sum()
    return solved / solved.sum()


def _is_dominant(affinity: np.ndarray, members: np.ndarray, shares: np.ndarray) -> bool:
    """Whether no one outside ``members`` earns at least the set's own payoff against it (the
    dominance condition on everyone, the global context of Hung & Kröse)."""
    block = affinity[np.ix_(members, members)]
    x = _characteristic_vector(block, shares)
    cohesion = float(x @ block @ x)
    outside = np.ones(affinity.shape[0], dtype=bool)
    outside[members] = False
    if not outside.any():
        return True
    earned = affinity[np.ix_(outside, members)] @ x
    return not bool(np.any(earned >= cohesion * (1.0 - _DOMINANCE_TOL)))


def dominant_set_labels(affinity: npt.ArrayLike, *, global_context: bool = True) -> np.ndarray:
    """Groups peeled one dominant set at a time, as per-person labels.

    Repeats, on the people not yet in a group: run :func:`replicator_dynamics`; the set is the
    people whose share exceeds :data:`SUPPORT` times the largest. It stops when the set has one
    member (nobody left is similar to anyone left) or, with ``global_context``, when the set is
    not dominant among everyone (see the module docstring). Everyone not in a group is alone.

    Args:
        affinity: (n, n) symmetric non-negative affinities (the diagonal is ignored).
        global_context: stop at the first set that is not dominant among everyone.

    Returns:
        (n,) int64 labels: groups numbered in the order they were found, then each person left
        alone with a label of their own (in row order).
    """
    matrix = np.array(affinity, dtype=np.float64, copy=True)
    n = matrix.shape[0]
    np.fill_diagonal(matrix, 0.0)
    labels = np.full(n, -1, dtype=np.int64)
    remaining = np.arange(n)
    group = 0
    while remaining.size >= 2:
        block = matrix[np.ix_(remaining, remaining)]
        shares = replicator_dynamics(block)
        inside = shares > SUPPORT * shares.max()
        if inside.sum() < 2 or float(shares @ block @ shares) <= 0.0:
            break
        members = remaining[inside]
        if global_context and not _is_dominant(matrix, members, shares[inside]):
            break
        labels[members] = group
        group += 1
        remaining = remaining[~inside]
    alone = labels < 0
    labels[alone] = group + np.arange(int(alone.sum()))
    return labels


def hung_krose_affinity(
    position: npt.ArrayLike, yaw: npt.ArrayLike, *, sigma: float, field_of_view: float
) -> np.ndarray:
    """Hung & Kröse's pairwise affinity: proximity, kept for pairs in each other's view.

    ``A[i, j] = exp(-d_ij² / (2 sigma²))`` when each of ``i`` and ``j`` has the other within
    ``field_of_view / 2`` of their orientation, else 0; the diagonal is 0.

    Args:
        position: (n, 2) positions, metres.
        yaw: (n,) orientations, radians.
        sigma: the Gaussian's width, metres.
        field_of_view: the whole angle of view, radians (2π: orientation is ignored).

    Returns:
        (n, n) float64 symmetric affinities in [0, 1].
    """
    position = np.asarray(position, dtype=np.float64)
    yaw = np.asarray(yaw, dtype=np.float64)
    dx = position[None, :, 0] - position[:, None, 0]  # dx[i, j]: from i to j
    dy = position[None, :, 1] - position[:, None, 1]
    distance2 = dx * dx + dy * dy
    bearing = np.arctan2(dy, dx)  # direction from i to j
    off = np.abs(wrap_angle(bearing - yaw[:, None]))  # how far j is from i's orientation
    seen = off <= field_of_view / 2.0
    mutual = seen & seen.T
    affinity = np.where(mutual, np.exp(-distance2 / (2.0 * sigma * sigma)), 0.0)
    np.fill_diagonal(affinity, 0.0)
    return affinity


class DominantSets(Estimator):
    """Dominant-sets detector (Hung & Kröse 2011) on proximity and mutual view.

    Follows the detector protocol: ``fit(frames) -> self`` (nothing to learn) and
    ``predict(frames)`` -> one full partition per frame, singletons included. Deterministic:
    the replicator dynamics start from the simplex's centre.

    Args:
        sigma: width of the proximity Gaussian, metres.
        field_of_view: whole angle within which each must have the other, radians.
        orientation: ``"body"`` or ``"head"`` (head yaw where seen, body yaw where not).
        global_context: stop peeling at the first set that is not dominant among everyone.
    """

    def __init__(
        self,
        *,
        sigma: float = SIGMA_M,
        field_of_view: float = FIELD_OF_VIEW_RAD,
        orientation: str = "body",
        global_context: bool = True,
    ) -> None:
        self.sigma = sigma
        self.field_of_view = field_of_view
        self.orientation = orientation
        self.global_context = global_context

    def _validate(self) -> tuple[float, float]:
        sigma = check_number("sigma", self.sigma, low=0.0, high=100.0, open_low=True)
        view = check_number("field_of_view", self.field_of_view, low=0.0, high=2 * np.pi)
        check_choice("orientation", self.orientation, ORIENTATIONS)
        if not isinstance(self.global_context, (bool, np.bool_)):
            raise ValueError(f"global_context must be True or False, got {self.global_context!r}")
        return sigma, view

    def frame_bytes(self, n_people: int) -> int:
        """Bytes it takes at its peak on one frame of ``n_people``: dense (n, n) affinities
        and the dynamics' copies of them, `CELL_BYTES` a cell."""
        return n_people * n_people * CELL_BYTES

    def fit(self, frames: Sequence[Frame]) -> DominantSets:
        """Checks the parameters and ``frames``; returns ``self`` (nothing to learn)."""
        self._validate()
        check_frames(frames)
        return self

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One partition per frame: groups in order of their first member's row."""
        sigma, view = self._validate()
        out = []
        for frame in check_frames(frames):
            affinity = hung_krose_affinity(
                frame.position,
                orientation_of(frame, self.orientation),
                sigma=sigma,
                field_of_view=view,
            )
            labels = dominant_set_labels(affinity, global_context=bool(self.global_context))
            out.append(labels_to_partition(frame.ids, labels))
        return out

    def __sklearn_is_fitted__(self) -> bool:
        return True

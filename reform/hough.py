"""Hough voting for F-formations: HVFF (Cristani et al., BMVC 2011) and its multi-scale form
(Setti et al., ICIP 2013).

**HVFF.** Where someone stands and faces is uncertain, so each person casts ``samples`` votes:
each vote is their pose perturbed by Gaussian noise (``position_sd`` on the position,
``orientation_sd`` on the orientation) and points at the spot ``stride`` in front of that pose,
where the o-space centre of their F-formation would be. Votes accumulate on the floor; an
o-space is a place that collects votes from several people at once. The accumulator is read
with the *weighted Boltzmann entropy* of the paper: at a candidate centre ``c``, each person's
share ``w_i(c)`` is the part of their votes that fall within ``radius`` of ``c`` (each vote
weighted by ``1 - (r / radius)²``, an Epanechnikov kernel), and the score is
``W * exp(H)`` with ``W`` the sum of the shares of the people counted and ``H`` the entropy of
those shares normalised (``exp(H)`` is the number of people voting there, counted evenly): a
centre backed equally by many people beats one crowded with a single person's votes. Groups are
found greedily: take the best centre backed by at least two people with a share of at least
``min_share`` each, make them a group, withdraw their votes, repeat; everyone left is alone.

**Multi-scale HVFF.** The o-space of a larger group is wider: people of a group of ``k`` stand
on a circle of radius ``r_k = spacing / (2 sin(π / k))`` (``spacing`` metres between
neighbours). Each person votes at every scale ``k = 2 .. max_size`` with ``stride = r_k``, and a
centre of scale ``k`` makes a group only when it is backed by exactly ``k`` people (at least
``max_size`` at the largest scale): each scale looks for the groups it is made for.

What differs from the papers, and why:

* **The accumulator.** The papers quantise the floor into a grid of cells. A grid has an origin
  and axes, so turning or moving the scene moves votes across cell borders and changes the
  groups. Here the cells are discs of ``radius`` centred on candidate centres (every person's
  first :data:`CANDIDATES` votes, the first being their noise-free vote), which turn and move
  with the scene.
* **The samples.** One set of noise draws comes from a generator seeded with
  ``random_state``, and every person's votes are that set applied to their pose: the same
  input always gives the same groups, whatever the order or the names of the people.
* The constants the papers leave open (``stride``, ``radius``, ``min_share``, the multi-scale
  ``spacing``) are options whose defaults were chosen on SALSA's training split alone (see the
  detectors' pages).

**Crowds.** Nothing in the method reaches beyond an accumulator cell: a person counts at a
centre only through their own votes within ``radius`` of it, so people whose votes never back a
common centre cannot change each other's groups. Up to :data:`CROWD_PEOPLE` people the
accumulator is a dense (centres x people) matrix; beyond, only the shares that make a backer are
kept and the frame is read part by part (:func:`hough_labels` says why the labels are the same,
numbering included, and ``tests/reform/test_hough_crowd.py`` checks it against the dense reading),
in time and memory that grow with the people and their votes rather than their square.
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from reform._params import ORIENTATIONS, check_choice, check_number, orientation_of
from reform.estimator import Estimator
from reform.frame import Frame, Group, check_frames
from reform.gcff import labels_to_partition

__all__ = [
    "CANDIDATES",
    "CROWD_PEOPLE",
    "MAX_SIZE",
    "MIN_SHARE",
    "MULTISCALE_RADIUS_M",
    "ORIENTATION_SD_RAD",
    "POSITION_SD_M",
    "RADIUS_M",
    "SAMPLES",
    "SPACING_M",
    "STRIDE_M",
    "Hvff",
    "MultiScaleHvff",
    "hough_labels",
    "scale_strides",
    "vote_noise",
]

# The open constants (stride, radius, min_share, spacing) are chosen on SALSA's training split
# alone, by benchmarks/choose_field_defaults.py.
STRIDE_M = 0.7  # metres: distance of the o-space centre in front of a person
SAMPLES = 100  # votes per person
POSITION_SD_M = 0.1  # metres: standard deviation of the position noise of a vote
ORIENTATION_SD_RAD = 0.25  # radians: standard deviation of the orientation noise of a vote
RADIUS_M = 0.5  # metres: radius of an accumulator cell (HVFF)
MULTISCALE_RADIUS_M = 0.5  # metres: the same for multi-scale HVFF
MIN_SHARE = 0.2  # a person backs a centre holding at least this share of their (kernel) votes
SPACING_M = 1.0  # metres between neighbours on a group's circle (multi-scale)
MAX_SIZE = 6  # the largest group size with a scale of its own (multi-scale)
CANDIDATES = 8  # votes of each person tried as candidate centres
RANDOM_STATE = 0  # the default seed of the votes' noise
CROWD_PEOPLE = 400  # beyond this many people the accumulator is read part by part (same labels)


def vote_noise(
    rng: np.random.Generator, *, samples: int, position_sd: float, orientation_sd: float
):
    """One set of vote perturbations: (samples, 2) position offsets in the voter's frame (metres)
    and (samples,) orientation offsets (radians). The first vote is unperturbed."""
    offset = rng.normal(0.0, position_sd, (samples, 2))
    turn = rng.normal(0.0, orientation_sd, samples)
    offset[0] = 0.0
    turn[0] = 0.0
    return offset, turn


def _votes(position, yaw, offset, turn, stride) -> np.ndarray:
    """(n, samples, 2) votes: each perturbed pose's point ``stride`` in front of it."""
    cos, sin = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    x = position[:, 0, None] + cos * offset[None, :, 0] - sin * offset[None, :, 1]
    y = position[:, 1, None] + sin * offset[None, :, 0] + cos * offset[None, :, 1]
    heading = yaw[:, None] + turn[None, :]
    return np.stack([x + stride * np.cos(heading), y + stride * np.sin(heading)], axis=2)


def _near_votes(votes: np.ndarray, candidates: int, radius: float) -> tuple[np.ndarray, ...]:
    """Every (candidate centre, vote) pair closer than ``radius``: the cell ``centre * n +
    voter`` of each and the vote's kernel weight ``1 - (r / radius)²``, in the order the
    accumulator sums them (the centres are every person's first ``candidates`` votes)."""
    n, samples, _ = votes.shape
    flat = votes.reshape(-1, 2)
    centres = votes[:, :candidates].reshape(-1, 2)
    near = cKDTree(centres).sparse_distance_matrix(cKDTree(flat), radius, output_type="ndarray")
    weight = 1.0 - (near["v"] / radius) ** 2
    voter = near["j"] // samples
    return near["i"].astype(np.int64) * n + voter, weight


def _shares(votes: np.ndarray, candidates: int, radius: float) -> np.ndarray:
    """(n * candidates, n) shares: the kernel-weighted part of each person's votes within
    ``radius`` of each candidate centre (every person's first ``candidates`` votes)."""
    n, samples, _ = votes.shape
    cell, weight = _near_votes(votes, candidates, radius)
    total = np.bincount(cell, weights=weight, minlength=n * candidates * n)
    return total.reshape(n * candidates, n) / samples


def _backers(
    votes: np.ndarray, candidates: int, radius: float, min_share: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The entries of :func:`_shares` that make a backer (share >= ``min_share``), without the
    dense matrix: (centre, person, share) by centre then person. Each share is summed over the
    same votes in the same order as :func:`_shares` sums it, so it is the same number."""
    n, samples, _ = votes.shape
    cell, weight = _near_votes(votes, candidates, radius)
    # A stable sort keeps each cell's votes in the order the dense accumulator adds them.
    order = np.argsort(cell, kind="stable")
    cell, weight = cell[order], weight[order]
    starts = np.diff(cell, prepend=-1) != 0  # cell numbers are >= 0
    keys = cell[starts]
    share = np.bincount(np.cumsum(starts) - 1, weights=weight, minlength=keys.size) / samples
    backs = share >= min_share
    centre, person = np.divmod(keys[backs], n)
    return centre, person, share[backs]


def scale_strides(spacing: float, max_size: int) -> np.ndarray:
    """(max_size - 1,) o-space radii of groups of 2 .. max_size people ``spacing`` apart on a
    circle: ``spacing / (2 sin(π / k))``, metres."""
    k = np.arange(2, max_size + 1)
    return spacing / (2.0 * np.sin(np.pi / k))


def _scores(share: np.ndarray, backs: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Weighted Boltzmann entropy score ``W * exp(H)`` of each candidate centre over its backers
    (``-inf`` for a centre whose number of backers is outside ``[low, high]``)."""
    count = backs.sum(axis=1)
    kept = np.where(backs, share, 0.0)
    # Sums run person by person (cumsum, not numpy's pairwise sum), so that a centre's score is
    # the same number whether its row spans the whole frame or only the people near it.
    total = np.cumsum(kept, axis=1)[:, -1] if kept.shape[1] else np.zeros(kept.shape[0])
    with np.errstate(divide="ignore", invalid="ignore"):
        p = kept / total[:, None]
        terms = np.where(kept > 0, p * np.log(p), 0.0)
        entropy = -np.cumsum(terms, axis=1)[:, -1] if kept.shape[1] else np.zeros(kept.shape[0])
    valid = (count >= low) & (count <= high)
    return np.where(valid, total * np.exp(entropy), -np.inf)


def _greedy(
    share: np.ndarray,
    backs: np.ndarray,
    owner: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
) -> list[tuple[float, int, np.ndarray]]:
    """The greedy reading of the accumulator: the best centre's backers are a group, their votes
    are withdrawn, and so on while a centre has a valid set of backers.

    Args:
        share: (centres, people) shares (only backers' are read).
        backs: (centres, people) whether each person backs each centre (changed in place).
        owner: (centres,) the person (column) whose vote each centre is.
        low, high: (centres,) the fewest and most backers a centre of each row's scale needs.

    Returns:
        The groups in the order they are taken: each one's score, row and members (columns).
    """
    # Backers only ever leave a centre: after each group only the centres it touched are
    # scored again.
    score = _scores(share, backs, low, high)
    free = np.ones(backs.shape[1], dtype=bool)
    taken = []
    while score.size and np.isfinite(score.max()):
        best = int(np.argmax(score))
        members = backs[best].copy()
        taken.append((float(score[best]), best, np.flatnonzero(members)))
        free &= ~members
        touched = backs[:, members].any(axis=1)
        backs[:, members] = False
        score[touched] = _scores(share[touched], backs[touched], low[touched], high[touched])
        score[~free[owner]] = -np.inf
    return taken


def _whole_frame(
    votes: list[np.ndarray],
    candidates: int,
    sizes: Sequence[tuple[int, int]],
    radius: float,
    min_share: float,
) -> list[np.ndarray]:
    """:func:`_greedy` on the dense accumulator of the whole frame (every centre by every
    person); the groups as members' rows, in the order taken."""
    n = votes[0].shape[0]
    share = np.concatenate([_shares(v, candidates, radius) for v in votes])
    owner = np.tile(np.repeat(np.arange(n), candidates), len(votes))
    low = np.repeat([s[0] for s in sizes], n * candidates)
    high = np.repeat([s[1] for s in sizes], n * candidates)
    backs = share >= min_share
    kept = backs.sum(axis=1) >= 2  # a centre with fewer than two backers never makes a group
    share, backs, owner = share[kept], backs[kept], owner[kept]
    low, high = np.maximum(low[kept], 2), high[kept]
    return [members for _, _, members in _greedy(share, backs, owner, low, high)]


def _by_parts(
    votes: list[np.ndarray],
    candidates: int,
    sizes: Sequence[tuple[int, int]],
    radius: float,
    min_share: float,
) -> list[np.ndarray]:
    """What :func:`_whole_frame` gives, read part by part (see :func:`hough_labels`): the votes
    of each scale (n, samples, 2) in, the groups as members' rows out, in the order taken."""
    n = votes[0].shape[0]
    per_scale = n * candidates
    centre, person, share = [], [], []
    for k, v in enumerate(votes):
        c, p, s = _backers(v, candidates, radius, min_share)
        centre.append(c + k * per_scale)
        person.append(p)
        share.append(s)
    centre, person, share = np.concatenate(centre), np.concatenate(person), np.concatenate(share)
    count = np.bincount(centre, minlength=len(votes) * per_scale)
    keep = count[centre] >= 2  # a centre with fewer than two backers never makes a group
    centre, person, share = centre[keep], person[keep], share[keep]
    owner = (centre % per_scale) // candidates
    # People joined through a centre (its owner and its backers) fall in one part.
    links = coo_array((np.ones(centre.size, dtype=np.int8), (owner, person)), shape=(n, n))
    _, part = connected_components(links, directed=False)
    low_of = np.array([max(s[0], 2) for s in sizes])
    high_of = np.array([s[1] for s in sizes])
    order = np.lexsort((person, centre, part[owner]))  # by part, then centre, then person
    centre, person, share, owner = centre[order], person[order], share[order], owner[order]
    bounds = np.flatnonzero(np.diff(part[owner])) + 1
    heads = []
    sequences = []
    for rows in np.split(np.arange(centre.size), bounds):
        if not rows.size:
            continue
        people, column = np.unique(np.concatenate([person[rows], owner[rows]]), return_inverse=True)
        column = column.ravel()
        rows_of, row = np.unique(centre[rows], return_inverse=True)
        row = row.ravel()
        dense = np.zeros((rows_of.size, people.size))
        dense[row, column[: rows.size]] = share[rows]
        backs = np.zeros(dense.shape, dtype=bool)
        backs[row, column[: rows.size]] = True
        local_owner = np.searchsorted(people, (rows_of % per_scale) // candidates)
        scale = rows_of // per_scale
        taken = _greedy(dense, backs, local_owner, low_of[scale], high_of[scale])
        sequence = [(score, int(rows_of[r]), people[m]) for score, r, m in taken]
        if sequence:
            heads.append((-sequence[0][0], sequence[0][1], len(sequences), 0))
            sequences.append(sequence)
    # The whole frame takes, at each step, the best centre of all (the first row among equals);
    # a part's own sequence does not depend on the others, so the next group of the whole frame
    # is the best of the parts' next groups.
    heapq.heapify(heads)
    groups = []
    while heads:
        _, _, which, at = heapq.heappop(heads)
        groups.append(sequences[which][at][2])
        if at + 1 < len(sequences[which]):
            score, row, _ = sequences[which][at + 1]
            heapq.heappush(heads, (-score, row, which, at + 1))
    return groups


def hough_labels(
    position: npt.ArrayLike,
    yaw: npt.ArrayLike,
    *,
    offset: np.ndarray,
    turn: np.ndarray,
    strides: Sequence[float],
    sizes: Sequence[tuple[int, int]],
    radius: float,
    min_share: float,
) -> np.ndarray:
    """Groups by Hough voting at one or several scales, as per-person labels.

    Up to :data:`CROWD_PEOPLE` people the accumulator is a dense (centres x people) matrix of
    shares. Beyond, only the shares that make a backer are kept, and the frame is read in
    parts: people joined by a centre (its owner and its backers) are in one part. A part's
    groups depend on its people alone (a centre is scored on its backers' shares, taking a
    group withdraws votes only from centres those people back, and voids only the centres they
    own), so each part's sequence of groups is the one the whole frame takes there, and the
    whole frame's order is the parts' sequences merged by taking the best next group (the first
    row among equal scores), as the whole frame does. Shares and scores are summed in the same
    order on both paths: the labels are the same, numbering included.

    Args:
        position: (n, 2) positions, metres.
        yaw: (n,) orientations, radians.
        offset, turn: the vote perturbations (:func:`vote_noise`).
        strides: the o-space distance of each scale, metres.
        sizes: for each scale, the (smallest, largest) number of backers a centre of that
            scale needs to make a group.
        radius: radius of an accumulator cell, metres.
        min_share: the share of a person's votes that makes them a backer of a centre.

    Returns:
        (n,) int64 labels: groups in the order they were found, then everyone alone.
    """
    position = np.asarray(position, dtype=np.float64)
    yaw = np.asarray(yaw, dtype=np.float64)
    n = position.shape[0]
    labels = np.full(n, -1, dtype=np.int64)
    groups = []
    if n >= 2:
        candidates = min(CANDIDATES, offset.shape[0])
        votes = [_votes(position, yaw, offset, turn, stride) for stride in strides]
        read = _whole_frame if n <= CROWD_PEOPLE else _by_parts
        groups = read(votes, candidates, sizes, radius, min_share)
    for group, members in enumerate(groups):
        labels[members] = group
    alone = labels < 0
    labels[alone] = len(groups) + np.arange(int(alone.sum()))
    return labels


class _HoughBase(Estimator):
    """What HVFF and its multi-scale form share: the votes' noise and the accumulator."""

    def _check_common(self) -> dict:
        values = {
            "samples": check_number("samples", self.samples, low=16, high=10_000, integer=True),
            "position_sd": check_number("position_sd", self.position_sd, low=0.0, high=10.0),
            "orientation_sd": check_number(
                "orientation_sd", self.orientation_sd, low=0.0, high=np.pi
            ),
            "radius": check_number("radius", self.radius, low=0.0, high=10.0, open_low=True),
            "min_share": check_number(
                "min_share", self.min_share, low=0.0, high=1.0, open_low=True
            ),
            "random_state": check_number(
                "random_state", self.random_state, low=0, high=2**32 - 1, integer=True
            ),
        }
        check_choice("orientation", self.orientation, ORIENTATIONS)
        return values

    def _scales(self) -> tuple[list[float], list[tuple[int, int]]]:
        raise NotImplementedError

    def fit(self, frames: Sequence[Frame]) -> _HoughBase:
        """Checks the parameters and ``frames``; returns ``self`` (nothing to learn)."""
        self._check_common()
        self._scales()
        check_frames(frames)
        return self

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One partition per frame: groups in order of their first member's row."""
        values = self._check_common()
        strides, sizes = self._scales()
        offset, turn = vote_noise(
            np.random.default_rng(values["random_state"]),
            samples=values["samples"],
            position_sd=values["position_sd"],
            orientation_sd=values["orientation_sd"],
        )
        out = []
        for frame in check_frames(frames):
            labels = hough_labels(
                frame.position,
                orientation_of(frame, self.orientation),
                offset=offset,
                turn=turn,
                strides=strides,
                sizes=sizes,
                radius=values["radius"],
                min_share=values["min_share"],
            )
            out.append(labels_to_partition(frame.ids, labels))
        return out

    def __sklearn_is_fitted__(self) -> bool:
        return True


class Hvff(_HoughBase):
    """HVFF (Cristani et al. 2011): Hough voting for o-space centres at one stride.

    Follows the detector protocol: ``fit(frames) -> self`` (nothing to learn) and
    ``predict(frames)`` -> one full partition per frame, singletons included. The votes' noise
    comes from ``numpy.random.default_rng(random_state)``.

    Args:
        stride: distance of the o-space centre in front of a person, metres.
        samples: votes per person.
        position_sd: standard deviation of a vote's position noise, metres.
        orientation_sd: standard deviation of a vote's orientation noise, radians.
        radius: radius of an accumulator cell, metres.
        min_share: share of a person's votes a centre must hold for them to back it.
        orientation: ``"body"`` or ``"head"`` (head yaw where seen, body yaw where not).
        random_state: seed of the votes' noise.
    """

    def __init__(
        self,
        *,
        stride: float = STRIDE_M,
        samples: int = SAMPLES,
        position_sd: float = POSITION_SD_M,
        orientation_sd: float = ORIENTATION_SD_RAD,
        radius: float = RADIUS_M,
        min_share: float = MIN_SHARE,
        orientation: str = "body",
        random_state: int = RANDOM_STATE,
    ) -> None:
        self.stride = stride
        self.samples = samples
        self.position_sd = position_sd
        self.orientation_sd = orientation_sd
        self.radius = radius
        self.min_share = min_share
        self.orientation = orientation
        self.random_state = random_state

    def _scales(self) -> tuple[list[float], list[tuple[int, int]]]:
        stride = check_number("stride", self.stride, low=0.0, high=100.0)
        return [stride], [(2, np.iinfo(np.int64).max)]


class MultiScaleHvff(_HoughBase):
    """Multi-scale HVFF (Setti et al. 2013): votes at the o-space radius of each group size.

    As :class:`Hvff`, with a scale per group size ``k = 2 .. max_size`` (stride
    ``spacing / (2 sin(π / k))``), a centre of scale ``k`` making a group of exactly ``k`` (at
    least ``max_size`` at the largest scale).

    Args:
        spacing: metres between neighbours on a group's circle.
        max_size: the largest group size with a scale of its own (2 to 20).
        samples: votes per person, at every scale.
        position_sd: standard deviation of a vote's position noise, metres.
        orientation_sd: standard deviation of a vote's orientation noise, radians.
        radius: radius of an accumulator cell, metres.
        min_share: share of a person's votes a centre must hold for them to back it.
        orientation: ``"body"`` or ``"head"`` (head yaw where seen, body yaw where not).
        random_state: seed of the votes' noise.
    """

    def __init__(
        self,
        *,
        spacing: float = SPACING_M,
        max_size: int = MAX_SIZE,
        samples: int = SAMPLES,
        position_sd: float = POSITION_SD_M,
        orientation_sd: float = ORIENTATION_SD_RAD,
        radius: float = MULTISCALE_RADIUS_M,
        min_share: float = MIN_SHARE,
        orientation: str = "body",
        random_state: int = RANDOM_STATE,
    ) -> None:
        self.spacing = spacing
        self.max_size = max_size
        self.samples = samples
        self.position_sd = position_sd
        self.orientation_sd = orientation_sd
        self.radius = radius
        self.min_share = min_share
        self.orientation = orientation
        self.random_state = random_state

    def _scales(self) -> tuple[list[float], list[tuple[int, int]]]:
        spacing = check_number("spacing", self.spacing, low=0.0, high=100.0, open_low=True)
        max_size = check_number("max_size", self.max_size, low=2, high=20, integer=True)
        strides = scale_strides(spacing, max_size).tolist()
        sizes = [(k, k) for k in range(2, max_size)] + [(max_size, np.iinfo(np.int64).max)]
        return strides, sizes

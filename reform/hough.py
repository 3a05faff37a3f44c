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
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree
from sklearn.base import BaseEstimator

from reform._params import ORIENTATIONS, check_choice, check_number, orientation_of
from reform.frame import Frame, Group, check_frames
from reform.gcff import labels_to_partition

__all__ = [
    "CANDIDATES",
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


def _shares(votes: np.ndarray, candidates: int, radius: float) -> np.ndarray:
    """(n * candidates, n) shares: the kernel-weighted part of each person's votes within
    ``radius`` of each candidate centre (every person's first ``candidates`` votes)."""
    n, samples, _ = votes.shape
    flat = votes.reshape(-1, 2)
    centres = votes[:, :candidates].reshape(-1, 2)
    near = cKDTree(centres).sparse_distance_matrix(cKDTree(flat), radius, output_type="coo_matrix")
    weight = 1.0 - (near.data / radius) ** 2
    voter = near.col // samples
    cell = near.row.astype(np.int64) * n + voter
    total = np.bincount(cell, weights=weight, minlength=centres.shape[0] * n)
    return total.reshape(centres.shape[0], n) / samples


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
    total = kept.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = kept / total[:, None]
        entropy = -np.where(kept > 0, p * np.log(p), 0.0).sum(axis=1)
    valid = (count >= low) & (count <= high)
    return np.where(valid, total * np.exp(entropy), -np.inf)


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
    group = 0
    if n >= 2:
        candidates = min(CANDIDATES, offset.shape[0])
        owner = np.repeat(np.arange(n), candidates)
        scales = [
            _shares(_votes(position, yaw, offset, turn, stride), candidates, radius)
            for stride in strides
        ]
        share = np.concatenate(scales)  # (scales * n * candidates, n)
        owner = np.tile(owner, len(scales))
        low = np.repeat([s[0] for s in sizes], n * candidates)
        high = np.repeat([s[1] for s in sizes], n * candidates)
        backs = share >= min_share
        # Backers only ever leave a centre, so a centre with fewer than two now never makes a
        # group: only the others are kept, and after each group only the centres it touched
        # are scored again.
        kept = backs.sum(axis=1) >= 2
        share, backs, owner = share[kept], backs[kept], owner[kept]
        low, high = np.maximum(low[kept], 2), high[kept]
        score = _scores(share, backs, low, high)
        free = np.ones(n, dtype=bool)
        while score.size and np.isfinite(score.max()):
            best = int(np.argmax(score))
            members = backs[best].copy()
            labels[members] = group
            group += 1
            free &= ~members
            touched = backs[:, members].any(axis=1)
            backs[:, members] = False
            score[touched] = _scores(share[touched], backs[touched], low[touched], high[touched])
            score[~free[owner]] = -np.inf
    alone = labels < 0
    labels[alone] = group + np.arange(int(alone.sum()))
    return labels


class _HoughBase(BaseEstimator):
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

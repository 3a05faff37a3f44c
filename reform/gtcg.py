"""GTCG: game-theoretic conversational groups (Vascon et al., CVIU 2016), one frame at a time.

Each person's *frustum*, where their attention goes, is a distribution on the floor in front of
them: a direction drawn around their orientation (a Gaussian of standard deviation a third of
half the aperture) and a distance drawn from ``Beta(0.8, 1.1)`` times the frustum's length
(the CVIU model of the authors' code). Two people whose frustums overlap attend to the same
place. The affinity of a pair is ``exp(-JS / sigma)``, with ``JS`` the Jensen-Shannon
divergence (base 2, in [0, 1]) of their frustums binned on the floor; the groups are the
evolutionarily stable strategies of the game with that payoff, found by the replicator dynamics
and peeled one at a time with Hung & Kröse's stopping rule (`reform.dominant_sets`).

What differs from the authors' MATLAB code, and why:

* **The bins.** The code bins every frustum on one 20 x 20 grid spanning the scene (the box
  around all samples, widened by one unit of length), so a bin's size depends on how large the
  scene is and on the unit of the data, and turning the scene turns the grid's axes against the
  people. Here each pair is binned on its own grid of square bins ``bin`` metres wide, centred
  on the pair's midpoint with one axis along the line joining them: the affinity is a function
  of the two people's relative pose alone, so that the groups do not change with the scene's
  size, place or heading. Pairs whose frustums cannot share a bin have ``JS = 1`` exactly
  (the divergence of disjoint distributions) and are not binned at all.
* **The samples.** The code draws fresh samples for every person from MATLAB's global random
  state. Here one set of ``samples`` (angle, distance) draws comes from a generator seeded with
  ``random_state`` and every person's frustum is that set turned and moved to their pose, so the
  answer is the same every time and for any order or naming of the people.
* **The replicator dynamics** run until no share moves by more than 1e-9 over 32 steps (the
  code stops at a step of 1e-5 in norm, after at most 3,000 steps), so that a share still
  decaying is not counted in a group; the support threshold is the code's (1e-5 of the largest
  share).
* **The multi-frame variant** (``frames`` > 1) averages the affinities of a frame and of the
  frames before it with equal weights, the authors' ``EQUAL`` mode; their default weights, from
  a multi-objective linear programme, are not implemented. The window is taken among the frames
  given to one ``predict`` call, by sequence and time.

**Crowds: the whole frame at once.** Frustums that share no bin keep the affinity
``exp(-1 / sigma)`` (0.19 at the default sigma; 0 only with ``zero_disjoint``), so every person
is joined to every other however far apart, and a set is kept only while its cohesion exceeds
what anyone far away earns from it, that same ``exp(-1 / sigma)``. With the replicator
dynamics' race over everyone left and the global stopping rule (`reform.dominant_sets` says
why they tie the groups to the whole frame), the frame cannot be cut into parts peeled on their
own with the same groups, and GTCG peels the whole frame at every size: the divergences are
computed only for pairs close enough to share a bin, but the peeling's time grows about as n^3
on crowds (``python benchmarks/bench_field_detectors.py --crowd``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from reform._params import ORIENTATIONS, check_choice, check_number, orientation_of
from reform.dominant_sets import dominant_set_labels
from reform.estimator import Estimator
from reform.frame import Frame, Group, check_frames
from reform.gcff import labels_to_partition

__all__ = [
    "APERTURE_DEG",
    "BETA_SHAPE",
    "BATCH_BYTES",
    "BIN_M",
    "CELL_BYTES",
    "LENGTH_M",
    "SAMPLES",
    "SIGMA",
    "Gtcg",
    "frustum_affinity",
    "frustum_samples",
]

LENGTH_M = 1.7  # metres: the frustum's length (the authors' Cocktail Party setting, 170 cm)
APERTURE_DEG = 160.0  # degrees: the frustum's aperture (the authors' setting, human view)
SAMPLES = 2000  # samples per frustum (the authors' setting)
# sigma and bin, which the paper sets per dataset, are chosen on SALSA's training split alone,
# by benchmarks/choose_field_defaults.py (which also tried lengths 1.0 and 2.5 m: 1.7 won).
SIGMA = 0.6  # the affinity's scale on the divergence
BIN_M = 0.2  # metres: the side of a square bin
BETA_SHAPE = (0.8, 1.1)  # the distance distribution of the CVIU frustum model
RANDOM_STATE = 0  # the default seed of the frustum samples
ZERO_DISJOINT = False  # the authors' code keeps exp(-1 / sigma) between disjoint frustums
_PAIRS_PER_BATCH = 64  # pairs binned together (a memory setting; results do not depend on it)
CELL_BYTES = 96  # bytes per (person, person) cell of a frame: divergences, affinities, the
# window's sum and the dominant sets' copies (`reform.dominant_sets.CELL_BYTES`)
BATCH_BYTES = 32 * 2**20  # bytes: one batch of pairs binned, whatever the crowd


def frustum_samples(
    rng: np.random.Generator, *, samples: int, length: float, aperture: float
) -> np.ndarray:
    """(samples, 2) points of one frustum in its owner's frame (owner at the origin, facing +x).

    Directions are ``N(0, aperture / 6)`` (a third of half the aperture, radians) and distances
    ``Beta(0.8, 1.1) * length``, as the CVIU model draws them.

    Args:
        rng: the generator drawn from (directions first, then distances).
        samples: how many points.
        length: the frustum's length, metres.
        aperture: the whole aperture, radians.
    """
    angle = rng.normal(0.0, aperture / 6.0, samples)
    radius = rng.beta(*BETA_SHAPE, samples) * length
    return np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)


def _posed(local: np.ndarray, position: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """(n, samples, 2): the frustum ``local`` turned by each yaw and moved to each position."""
    cos, sin = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    x = position[:, 0, None] + cos * local[None, :, 0] - sin * local[None, :, 1]
    y = position[:, 1, None] + sin * local[None, :, 0] + cos * local[None, :, 1]
    return np.stack([x, y], axis=2)


def _pair_divergence(
    points: np.ndarray,
    position: np.ndarray,
    yaw: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    *,
    bin_size: float,
    reach: float,
) -> np.ndarray:
    """Jensen-Shannon divergences (base 2) of the binned frustums of the pairs
    ``(first[k], second[k])``, each binned on a grid of its own (see the module docstring)."""
    delta = position[second] - position[first]
    distance = np.hypot(delta[:, 0], delta[:, 1])
    # The pair's axis: along the line joining them; for two people on one spot, the mean of
    # their headings (symmetric in the two, and turning with the scene).
    mean_heading = np.arctan2(
        np.sin(yaw[first]) + np.sin(yaw[second]), np.cos(yaw[first]) + np.cos(yaw[second])
    )
    angle = np.where(distance > 1e-9, np.arctan2(delta[:, 1], delta[:, 0]), mean_heading)
    cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
    middle = 0.5 * (position[first] + position[second])
    half = int(np.ceil(reach / bin_size)) + 1  # bins on each side of the midpoint
    width = 2 * half
    cells = width * width
    pairs = first.size
    counts = []
    # Every sample lies within ``reach`` of the midpoint, so ``u / bin_size + half`` is in
    # (0, width): truncation is the floor, and no bin index needs clipping.
    cos, sin = cos / bin_size, sin / bin_size
    base = (np.arange(pairs) * cells)[:, None]
    for who in (first, second):
        x = points[who, :, 0] - middle[:, 0, None]  # (pairs, samples)
        y = points[who, :, 1] - middle[:, 1, None]
        iu = (cos * x + sin * y + half).astype(np.int64)
        iv = (cos * y - sin * x + half).astype(np.int64)
        key = (base + iu * width + iv).ravel()
        counts.append(np.bincount(key, minlength=pairs * cells).reshape(pairs, cells))
    p = counts[0] / points.shape[1]
    q = counts[1] / points.shape[1]
    m = 0.5 * (p + q)
    with np.errstate(divide="ignore", invalid="ignore"):
        kl_p = np.where(p > 0, p * np.log2(p / m), 0.0).sum(axis=1)
        kl_q = np.where(q > 0, q * np.log2(q / m), 0.0).sum(axis=1)
    return np.clip(0.5 * (kl_p + kl_q), 0.0, 1.0)


def frustum_affinity(
    position: npt.ArrayLike,
    yaw: npt.ArrayLike,
    *,
    local: np.ndarray,
    sigma: float,
    bin_size: float,
    zero_disjoint: bool = False,
) -> np.ndarray:
    """GTCG's pairwise affinities ``exp(-JS / sigma)`` of everyone's frustums.

    Args:
        position: (n, 2) positions, metres.
        yaw: (n,) orientations, radians.
        local: (samples, 2) frustum points in the owner's frame (:func:`frustum_samples`).
        sigma: the scale on the divergence (> 0).
        bin_size: the side of a square bin, metres.
        zero_disjoint: subtract ``exp(-1 / sigma)``, the affinity of frustums that share no
            bin, so that people who attend to different places have none.

    Returns:
        (n, n) float64 symmetric affinities in [exp(-1/sigma), 1] (in [0, 1 - exp(-1/sigma)]
        with ``zero_disjoint``), zero diagonal.
    """
    position = np.asarray(position, dtype=np.float64)
    yaw = np.asarray(yaw, dtype=np.float64)
    n = position.shape[0]
    divergence = np.ones((n, n))
    if n >= 2:
        reach = float(np.max(np.hypot(local[:, 0], local[:, 1]))) if local.size else 0.0
        # Frustums further apart than this share no bin: their divergence is 1.
        near = cKDTree(position).query_pairs(
            2.0 * reach + 2.0 * np.sqrt(2.0) * bin_size, output_type="ndarray"
        )
        if near.size:
            points = _posed(local, position, yaw)
            limit = float(np.max(np.hypot(*(position[near[:, 1]] - position[near[:, 0]]).T)))
            for start in range(0, len(near), _PAIRS_PER_BATCH):
                batch = near[start : start + _PAIRS_PER_BATCH]
                js = _pair_divergence(
                    points,
                    position,
                    yaw,
                    batch[:, 0],
                    batch[:, 1],
                    bin_size=bin_size,
                    reach=limit / 2.0 + reach,
                )
                divergence[batch[:, 0], batch[:, 1]] = js
                divergence[batch[:, 1], batch[:, 0]] = js
    affinity = np.exp(-divergence / sigma)
    if zero_disjoint:
        affinity -= np.exp(-1.0 / sigma)
    np.fill_diagonal(affinity, 0.0)
    return affinity


def _window_affinity(
    frames: Sequence[Frame], affinities: list[np.ndarray], k: int, window: int
) -> np.ndarray:
    """The affinity of frame ``k`` averaged with equal weights over it and the ``window - 1``
    frames before it of its sequence in ``frames`` (earlier times only; the authors' ``EQUAL``
    weights). A pair of frame ``k`` that a past frame lacks counts 0 there, as the authors' code
    pads missing people with zeros."""
    frame = frames[k]
    if window <= 1:
        return affinities[k]
    past = [
        j for j in range(k) if frames[j].sequence == frame.sequence and frames[j].time < frame.time
    ]
    past = sorted(past, key=lambda j: frames[j].time)[-(window - 1) :]
    total = affinities[k].copy()
    for j in past:
        rows = {int(i): r for r, i in enumerate(frames[j].ids.tolist())}
        at = np.array([rows.get(int(i), -1) for i in frame.ids.tolist()], dtype=np.int64)
        seen = at >= 0
        block = np.zeros_like(total)
        block[np.ix_(seen, seen)] = affinities[j][np.ix_(at[seen], at[seen])]
        total += block
    return total / (1 + len(past))


class Gtcg(Estimator):
    """GTCG detector (Vascon et al. 2016), per frame, on frustum affinities.

    Follows the detector protocol: ``fit(frames) -> self`` (nothing to learn) and
    ``predict(frames)`` -> one full partition per frame, singletons included. The frustum
    samples come from ``numpy.random.default_rng(random_state)``: the same input always gives
    the same groups.

    Args:
        length: the frustum's length, metres.
        aperture: the frustum's whole aperture, degrees.
        samples: samples per frustum.
        sigma: the affinity's scale on the Jensen-Shannon divergence (base 2).
        bin: the side of a square bin of the frustum histograms, metres.
        orientation: ``"head"`` (the paper's, where seen; body yaw where not) or ``"body"``.
        global_context: stop peeling at the first set that is not dominant among everyone.
        zero_disjoint: take ``exp(-1 / sigma)``, the affinity of frustums sharing no bin, off
            every affinity.
        frames: frames whose affinities are averaged (equal weights): the frame and the
            ``frames - 1`` before it of its sequence among those predicted together; 1 is the
            per-frame detector.
        random_state: seed of the frustum samples.
    """

    def __init__(
        self,
        *,
        length: float = LENGTH_M,
        aperture: float = APERTURE_DEG,
        samples: int = SAMPLES,
        sigma: float = SIGMA,
        bin: float = BIN_M,  # noqa: A002 - the option's name
        orientation: str = "body",
        global_context: bool = True,
        zero_disjoint: bool = ZERO_DISJOINT,
        frames: int = 1,
        random_state: int = RANDOM_STATE,
    ) -> None:
        self.length = length
        self.aperture = aperture
        self.samples = samples
        self.sigma = sigma
        self.bin = bin
        self.orientation = orientation
        self.global_context = global_context
        self.zero_disjoint = zero_disjoint
        self.frames = frames
        self.random_state = random_state

    def _validate(self) -> dict:
        values = {
            "length": check_number("length", self.length, low=0.0, high=100.0, open_low=True),
            "aperture": check_number("aperture", self.aperture, low=0.0, high=360.0, open_low=True),
            "samples": check_number("samples", self.samples, low=10, high=100_000, integer=True),
            "sigma": check_number("sigma", self.sigma, low=0.0, high=100.0, open_low=True),
            "bin": check_number("bin", self.bin, low=0.0, high=100.0, open_low=True),
            "frames": check_number("frames", self.frames, low=1, high=100, integer=True),
            "random_state": check_number(
                "random_state", self.random_state, low=0, high=2**32 - 1, integer=True
            ),
        }
        check_choice("orientation", self.orientation, ORIENTATIONS)
        for name in ("global_context", "zero_disjoint"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f"{name} must be True or False, got {getattr(self, name)!r}")
        return values

    def frame_bytes(self, n_people: int) -> int:
        """Bytes it takes at its peak on one frame of ``n_people``: `CELL_BYTES` a (person,
        person) cell and one batch of pairs binned (`BATCH_BYTES`). ``predict`` also keeps each
        frame's (n, n) affinities while it runs, for the multi-frame window."""
        return n_people * n_people * CELL_BYTES + BATCH_BYTES

    def fit(self, frames: Sequence[Frame]) -> Gtcg:
        """Checks the parameters and ``frames``; returns ``self`` (nothing to learn)."""
        self._validate()
        check_frames(frames)
        return self

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One partition per frame: groups in order of their first member's row."""
        values = self._validate()
        local = frustum_samples(
            np.random.default_rng(values["random_state"]),
            samples=values["samples"],
            length=values["length"],
            aperture=np.deg2rad(values["aperture"]),
        )
        frames = check_frames(frames)
        affinities = [
            frustum_affinity(
                frame.position,
                orientation_of(frame, self.orientation),
                local=local,
                sigma=values["sigma"],
                bin_size=values["bin"],
                zero_disjoint=bool(self.zero_disjoint),
            )
            for frame in frames
        ]
        out = []
        for k, frame in enumerate(frames):
            affinity = _window_affinity(frames, affinities, k, values["frames"])
            labels = dominant_set_labels(affinity, global_context=bool(self.global_context))
            out.append(labels_to_partition(frame.ids, labels))
        return out

    def __sklearn_is_fitted__(self) -> bool:
        return True

"""What a recording of a place shows without its groups: the statistics a venue twin is fitted to.

`measure_place` reads positions, orientations, times and who is present, never the ground truth.
Every statistic is a plain float (NaN where the frames cannot say), so that the real recording
and its twin are measured by the same function and set side by side in ``twin.json``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from reform.frame import Frame, wrap_angle

__all__ = [
    "CLUMP_LINK",
    "CODINGS",
    "DETECTOR_SHAPE_SIZE",
    "SHAPE_SIZE",
    "PlaceStatistics",
    "detector_shape",
    "measure_place",
    "nearest_neighbour_distances",
    "spacing_shape",
    "standing_share",
]

# Orientation codings looked for, in directions per turn (the field's: 4, 8, 24).
CODINGS = (4, 8, 12, 16, 24, 36, 72)
CODING_TOLERANCE_RAD = 1e-3  # radians: a yaw this close to a coded direction is on it
STILL_M_PER_S = 0.15  # metres per second: slower than this between two frames is standing still
MAX_GAP_STEPS = 1.5  # consecutive frames are at most this many median steps apart
RAYLEIGH_MEDIAN = math.sqrt(2.0 * math.log(2.0)) * math.sqrt(2.0)  # |difference of two jitters|
HALF_NORMAL_MEDIAN = 0.6744897501960817 * math.sqrt(2.0)  # |difference of two yaw jitters|
CLUMP_LINK = 1.3  # median nearest-neighbour distances: people closer than this are one clump
VOTE_AHEAD = (0.3, 0.6, 0.9)  # median nearest-neighbour distances: o-space votes this far ahead
VOTE_LINK = 0.5  # median nearest-neighbour distances: votes closer than this are one clump
SMALL_CLUMP_PEOPLE = 64  # people: clumps of frames up to this size are found by squaring the links
SHAPE_SIZE = 16  # entries of `spacing_shape`
DETECTOR_FRAMES = 150  # frames (evenly spread) the detectors of `detector_shape` run on
DETECTOR_PERSON_FRAMES = 15_000  # ... and at most this many people in all (fewer frames of crowds)
STANDING_M_PER_S = 0.3  # metres per second: slower than this over a second is standing
STANDING_WINDOW_S = (1.0, 3.0)  # seconds: the interval a speed is measured over, at least, at most
DETECTOR_SHAPE_SIZE = 4  # entries of `detector_shape`
SHORT_STRIDE_M = 0.4  # metres: the stride of the GCFF `detector_shape` compares with the default


@dataclass(frozen=True)
class PlaceStatistics:
    """The label-free statistics of a recording.

    Attributes:
        frames: frames measured.
        sequences: recordings (sequences) among them.
        rate_hz: frames per second (the inverse of the median step within a sequence).
        duration_s: median length of a sequence, seconds.
        people_median, people_q10, people_q90: humans per frame.
        arrivals_per_min: people who appear (were not in the frame before), per minute.
        dropout: share of a person's frames missing between two frames that hold them.
        nn_q10, nn_median, nn_q90: every person's distance to the nearest other person, metres.
        extent_m: median over frames of the square root of the area of the box holding
            everyone, metres.
        density_per_m2: median over frames of the humans per square metre of that box.
        directions: orientations coded in this many directions (0: continuous).
        head_share: share of person-frames with a head pose.
        yaw_is_head: share of those whose recorded yaw is the head's yaw.
        position_jitter_m: per-axis standard deviation of position between frames of people
            standing still, metres.
        yaw_jitter_rad: standard deviation of yaw between frames of people standing still,
            radians (0 when orientations are coded).
    """

    frames: int
    sequences: int
    rate_hz: float
    duration_s: float
    people_median: float
    people_q10: float
    people_q90: float
    arrivals_per_min: float
    dropout: float
    nn_q10: float
    nn_median: float
    nn_q90: float
    extent_m: float
    density_per_m2: float
    directions: int
    head_share: float
    yaw_is_head: float
    position_jitter_m: float
    yaw_jitter_rad: float

    def to_json(self) -> dict[str, Any]:
        return {k: _rounded(v) for k, v in asdict(self).items()}


def _rounded(value: Any) -> Any:
    if isinstance(value, float):
        return None if not math.isfinite(value) else float(f"{value:.6g}")
    return value


def nearest_neighbour_distances(frames: Sequence[Frame]) -> np.ndarray:
    """Every person's distance to the nearest other person, in every frame of two or more
    people (annotated or not): (n,) in the frames' unit."""
    out = []
    for frame in frames:
        if frame.n_people < 2:
            continue
        p = frame.position
        d = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
        np.fill_diagonal(d, np.inf)
        out.append(d.min(axis=1))
    return np.concatenate(out) if out else np.zeros(0)


def _clump_sizes(d: np.ndarray, link: float) -> np.ndarray:
    """(n,) the size of each person's clump: people linked, in a chain, by distances under
    ``link`` (``d`` (n, n) pairwise distances, infinite on the diagonal).

    A frame of up to `SMALL_CLUMP_PEOPLE` people: who reaches whom, the links' matrix squared
    until it stops growing (chains of 2, 4, 8 ... links; a fit measures tens of thousands of
    such frames, where scipy's graph routine spends most of its time setting up); a larger
    one: scipy's connected components."""
    linked = d < link
    n = len(linked)
    if n <= SMALL_CLUMP_PEOPLE:
        reach = linked.astype(np.float64)
        np.fill_diagonal(reach, 1.0)
        while True:
            wider = (reach @ reach > 0.0).astype(np.float64)
            if np.array_equal(wider, reach):
                return reach.sum(axis=1).astype(np.int64)
            reach = wider
    from scipy.sparse.csgraph import connected_components

    _, label = connected_components(linked, directed=False)
    return np.bincount(label)[label]


def _votes(position: np.ndarray, yaw: np.ndarray, median: float) -> np.ndarray:
    """(n,) the size of each person's o-space vote clump, the largest over the distances ahead
    of `VOTE_AHEAD` (see `spacing_shape`)."""
    facing = np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
    sizes = np.ones(len(position), dtype=np.int64)
    for ahead in VOTE_AHEAD:
        v = position + ahead * median * facing
        d = np.hypot(v[:, None, 0] - v[None, :, 0], v[:, None, 1] - v[None, :, 1])
        np.fill_diagonal(d, np.inf)
        sizes = np.maximum(sizes, _clump_sizes(d, VOTE_LINK * median))
    return sizes


def spacing_shape(frames: Sequence[Frame]) -> np.ndarray:
    """How people stand relative to their spacing, free of the unit. (SHAPE_SIZE,):

    - 0-5: the 10, 25, 75 and 90 % quantiles of the nearest-neighbour distance and the medians
      of the second and third nearest, each over the median nearest-neighbour distance;
    - 6: the share of people whose nearest neighbour is more than 1.5 medians away (apart);
    - 7-8: the median and 75 % quantile of how far each person faces away from their nearest
      neighbour (radians, in [0, pi]);
    - 9-11: the 25, 50 and 75 % quantiles of how far a person and their nearest neighbour are
      from facing a common point (radians, in [0, pi]): with ``a`` the angle from the person's
      direction to the neighbour to their yaw and ``b`` the angle from the neighbour's direction
      to the person to the neighbour's yaw, ``|a + b|``, which is 0 when both face a point on the
      same side at the same angle, as members of one o-space do whatever its size (label-free
      evidence of o-spaces and of the noise on facings);
    - 12-13: clumps, people linked in a chain by distances under `CLUMP_LINK` medians: the mean
      size of the clump a person stands in (over people not alone in one) and the share of
      people in clumps of 4 or more (how large groups are and how close groups stand);
    - 14-15: o-space votes, the point each of `VOTE_AHEAD` medians ahead of each person,
      linked in a chain by distances under `VOTE_LINK` medians (each distance ahead on its
      own, a person's clump the largest of them, so that o-spaces of every size are found):
      the share of people whose vote is alone and the mean size of a vote's clump over the
      others (label-free evidence of how many people share an o-space, which clumps of bodies
      blur when groups stand close).
    """
    near, facing, common, clumps, votes = [], [], [], [], []
    for frame in frames:
        if frame.n_people < 4:
            continue
        p = frame.position
        d = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
        np.fill_diagonal(d, np.inf)
        near.append(np.sort(d, axis=1)[:, :3])
        nearest = np.argmin(d, axis=1)
        to = p[nearest] - p
        towards = np.arctan2(to[:, 1], to[:, 0])
        a = wrap_angle(frame.yaw - towards)
        b = wrap_angle(frame.yaw[nearest] - towards - math.pi)
        facing.append(np.abs(a))
        common.append(np.abs(wrap_angle(a + b)))
        clumps.append(d)
        votes.append((p, frame.yaw))
    if not near:
        return np.full(SHAPE_SIZE, np.nan)
    k = np.concatenate(near)
    median = float(np.median(k[:, 0]))
    quantiles = np.quantile(k[:, 0], [0.1, 0.25, 0.75, 0.9]) / median
    away = np.concatenate(facing)
    sizes = np.concatenate([_clump_sizes(d, CLUMP_LINK * median) for d in clumps])
    together = sizes[sizes > 1]
    voted = np.concatenate([_votes(p, yaw, median) for p, yaw in votes])
    shared = voted[voted > 1]
    return np.array(
        [*quantiles, np.median(k[:, 1]) / median, np.median(k[:, 2]) / median,
         float(np.mean(k[:, 0] > 1.5 * median)), np.median(away), np.quantile(away, 0.75),
         *np.quantile(np.concatenate(common), [0.25, 0.5, 0.75]),
         float(together.mean()) if together.size else 1.0, float(np.mean(sizes >= 4)),
         float(np.mean(voted == 1)), float(shared.mean()) if shared.size else 1.0]
    )  # fmt: skip


def _by_sequence(frames: Sequence[Frame]) -> list[list[Frame]]:
    runs: dict[str, list[Frame]] = {}
    for frame in frames:
        runs.setdefault(frame.sequence, []).append(frame)
    return [sorted(run, key=lambda f: f.time) for run in runs.values()]


def _coding(yaw: np.ndarray) -> int:
    """The number of directions every yaw is coded in, or 0 for continuous orientations."""
    if yaw.size == 0:
        return 0
    for k in CODINGS:
        step = 2.0 * math.pi / k
        off = np.abs(wrap_angle(yaw - np.round(yaw / step) * step))
        if np.all(off < CODING_TOLERANCE_RAD):
            return k
    return 0


def measure_place(frames: Sequence[Frame]) -> PlaceStatistics:
    """The statistics of ``frames`` (any order; grouped by sequence, ordered by time).

    Only positions, yaws, head poses, ids, kinds, times and sequences are read: the frames'
    groups never are.
    """
    frames = list(frames)
    runs = _by_sequence(frames)
    steps = np.concatenate([np.diff([f.time for f in run]) for run in runs if len(run) > 1] or [[]])
    steps = steps[steps > 0]
    step = float(np.median(steps)) if steps.size else math.nan
    durations = [
        run[-1].time - run[0].time + (step if math.isfinite(step) else 0.0) for run in runs
    ]

    humans = np.array([int(np.sum(~f.is_robot)) for f in frames], dtype=np.float64)
    nn = nearest_neighbour_distances(frames)
    extents, densities = [], []
    for frame in frames:
        p = frame.position[~frame.is_robot]
        if len(p) < 2:
            continue
        area = float(np.prod(np.maximum(np.ptp(p, axis=0), 1e-9)))
        extents.append(math.sqrt(area))
        densities.append(len(p) / max(area, 1e-9))

    yaw = np.concatenate([f.yaw for f in frames]) if frames else np.zeros(0)
    head_seen = head_same = person_frames = 0
    for frame in frames:
        person_frames += frame.n_people
        if frame.head_yaw is not None:
            seen = ~np.isnan(frame.head_yaw)
            head_seen += int(seen.sum())
            diff = np.abs(wrap_angle(frame.yaw[seen] - frame.head_yaw[seen]))
            head_same += int(np.sum(diff < CODING_TOLERANCE_RAD))

    moves, turns = [], []
    arrivals = missed = held = 0
    for run in runs:
        for k, (a, b) in enumerate(zip(run, run[1:], strict=False)):
            dt = b.time - a.time
            if not math.isfinite(step) or dt <= 0 or dt > MAX_GAP_STEPS * step:
                continue
            where = {int(i): j for j, i in enumerate(a.ids)}
            for j, i in enumerate(b.ids):
                prev = where.get(int(i))
                if prev is None:
                    arrivals += 1
                    continue
                move = float(np.hypot(*(b.position[j] - a.position[prev])))
                if move < STILL_M_PER_S * dt:
                    moves.append(move)
                    turns.append(abs(float(wrap_angle(b.yaw[j] - a.yaw[prev]))))
            if k + 2 < len(run):
                c = run[k + 2]
                both = set(a.ids.tolist()) & set(c.ids.tolist())
                held += len(both)
                missed += len(both - set(b.ids.tolist()))
    directions = _coding(yaw)
    minutes = sum(durations) / 60.0
    return PlaceStatistics(
        frames=len(frames),
        sequences=len(runs),
        rate_hz=1.0 / step if math.isfinite(step) and step > 0 else math.nan,
        duration_s=float(np.median(durations)) if durations else math.nan,
        people_median=_quantile(humans, 0.5),
        people_q10=_quantile(humans, 0.1),
        people_q90=_quantile(humans, 0.9),
        arrivals_per_min=arrivals / minutes if minutes > 0 else math.nan,
        dropout=missed / held if held else 0.0,
        nn_q10=_quantile(nn, 0.1),
        nn_median=_quantile(nn, 0.5),
        nn_q90=_quantile(nn, 0.9),
        extent_m=_quantile(np.array(extents), 0.5),
        density_per_m2=_quantile(np.array(densities), 0.5),
        directions=directions,
        head_share=head_seen / person_frames if person_frames else 0.0,
        yaw_is_head=head_same / head_seen if head_seen else 0.0,
        position_jitter_m=float(np.median(moves)) / RAYLEIGH_MEDIAN if moves else 0.0,
        yaw_jitter_rad=(
            float(np.median(turns)) / HALF_NORMAL_MEDIAN if turns and directions == 0 else 0.0
        ),
    )


def standing_share(frames: Sequence[Frame]) -> float:
    """The share of people standing: of every human seen twice in a sequence, `STANDING_WINDOW_S`
    apart (the first frame a second or more later, three at most), how many moved slower than
    `STANDING_M_PER_S` (positions in metres; measured over a second or more, so that a tracker's
    jitter at a high frame rate does not read as walking). NaN when no one is seen twice so.

    Only ids, kinds, positions, times and sequences are read."""
    shortest, longest = STANDING_WINDOW_S
    standing = seen = 0
    for run in _by_sequence(frames):
        times = np.array([f.time for f in run], dtype=np.float64)
        later = np.searchsorted(times, times + shortest - 1e-9)
        for a, k in zip(run, later.tolist(), strict=True):
            if k >= len(run) or run[k].time - a.time > longest:
                continue
            b = run[k]
            where = {int(i): j for j, i in enumerate(b.ids[~b.is_robot])}
            humans = a.position[~a.is_robot]
            after = b.position[~b.is_robot]
            ids = a.ids[~a.is_robot].tolist()
            pairs = [(j, where[i]) for j, i in enumerate(ids) if i in where]
            if not pairs:
                continue
            rows, cols = np.array(pairs).T
            speed = np.hypot(*(after[cols] - humans[rows]).T) / (b.time - a.time)
            standing += int(np.sum(speed < STANDING_M_PER_S))
            seen += len(pairs)
    return standing / seen if seen else math.nan


def _quantile(values: np.ndarray, q: float) -> float:
    return float(np.quantile(values, q)) if values.size else math.nan


def detector_shape(frames: Sequence[Frame]) -> np.ndarray:
    """How fixed detectors group the frames, and how much they agree, without any label:
    (DETECTOR_SHAPE_SIZE,), on at most `DETECTOR_FRAMES` frames of four or more people spread
    over the recording, fewer for crowds (`DETECTOR_PERSON_FRAMES` people in all, the frames'
    median people counted), positions in metres:

    - 0: the share of people GCFF (its catalogue settings) puts in a group of two or more;
    - 1: the mean size of those groups;
    - 2-3: the F1 at T = 2/3 of GCFF with a shorter stride (`SHORT_STRIDE_M`) and of the
      proximity baseline (its catalogue distance), each scored against GCFF's own groups: where
      detectors disagree, a place is hard to read, whatever its truth (1 where none of them
      finds a group).

    Every frame's groups are removed first: the detectors' groups are all it reads.
    """
    from fractions import Fraction

    from reform.detectors import make_detector, run_detector
    from reform.metrics import evaluate

    crowded = [f for f in frames if f.n_people >= 4]
    if not crowded:
        return np.full(DETECTOR_SHAPE_SIZE, math.nan)
    people = float(np.median([f.n_people for f in crowded]))
    most = max(1, min(DETECTOR_FRAMES, int(DETECTOR_PERSON_FRAMES // people)))
    step = max(1, len(crowded) // most)
    crowded = [f.replace(groups=None) for f in crowded[::step][:most]]
    base = run_detector("gcff", make_detector("gcff"), crowded)
    people = sum(f.n_people for f in crowded)
    grouped = [len(g) for p in base for g in p if len(g) >= 2]
    share = sum(grouped) / people
    size = float(np.mean(grouped)) if grouped else 1.0
    truth = [
        f.replace(groups=tuple(tuple(g) for g in p)) for f, p in zip(crowded, base, strict=True)
    ]
    agreement = []
    for name, options in (("gcff", {"stride": SHORT_STRIDE_M}), ("proximity", {})):
        other = run_detector(name, make_detector(name, **options), crowded)
        scores = evaluate(truth, other, thresholds=(Fraction(2, 3),))
        agreement.append(float(scores.at(Fraction(2, 3)).f1))
    return np.array([share, size, *agreement])

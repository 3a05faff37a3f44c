"""Calibration statistics: how a dataset's F-formations and pairs compare with another's.

One measuring instrument for every dataset, real or synthetic:

* :func:`characterise_dataset` measures the Tightness and Symmetry of every ground-truth
  F-formation (see :mod:`reform.characterisation`), summarised by group size, and the pair
  features (Distance, Effort Angle; :mod:`reform.features`) of every pair of the annotated
  frames with its label (1 = same F-formation).
* :func:`anova_by_size` and :func:`tukey_by_size` test whether a measure differs between group
  sizes (one-way ANOVA, Tukey's HSD), as the paper does.
* :func:`compare` puts a candidate (a synthetic scenario) beside a reference (SALSA, Babble):
  mean Tightness and Symmetry differences by group size, and two-sample Kolmogorov-Smirnov
  statistics of Distance and Effort Angle for in-group and out-of-group pairs.
  :meth:`Comparison.within_tolerance` is the calibration target: the candidate's mean Tightness
  within 0.1 m of the reference's for every group size the reference holds (with at least
  :data:`MIN_GROUPS` groups).

:data:`PAPER_CHARACTERISATION` holds the paper's published means, with their provenance.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np
from scipy import stats

from reform.characterisation import GroupShapes, characterise
from reform.features import DISTANCE, EFFORT_ANGLE, batch_pair_features, pair_indices
from reform.frame import Dataset, Frame
from reform.json_values import json_float, json_record

__all__ = [
    "CONFIDENCE_LEVEL",
    "IN_GROUP",
    "MEASURES",
    "MIN_GROUPS",
    "OUT_OF_GROUP",
    "PAIR_FEATURES",
    "PAIR_KINDS",
    "PAPER_CHARACTERISATION",
    "SYMMETRY",
    "TIGHTNESS",
    "TIGHTNESS_TOLERANCE_M",
    "UNITS",
    "Anova",
    "Characterisation",
    "Comparison",
    "KsResult",
    "PairSamples",
    "PaperAnova",
    "PaperCharacterisation",
    "SizeStats",
    "Tukey",
    "TukeyPair",
    "anova_by_size",
    "characterise_dataset",
    "compare",
    "eligible_sizes",
    "pair_feature_samples",
    "paper_characterisation_for",
    "tukey_by_size",
]

TIGHTNESS = "tightness"  # metres
SYMMETRY = "symmetry"  # degrees
MEASURES = (TIGHTNESS, SYMMETRY)
UNITS = MappingProxyType({TIGHTNESS: "m", SYMMETRY: "deg", DISTANCE: "m", EFFORT_ANGLE: "rad"})

PAIR_FEATURES = (DISTANCE, EFFORT_ANGLE)
IN_GROUP = "in-group"  # pairs in the same ground-truth F-formation (label 1)
OUT_OF_GROUP = "out-of-group"  # every other pair (label 0)
PAIR_KINDS = (IN_GROUP, OUT_OF_GROUP)

MIN_GROUPS = 5  # groups of one size needed before its mean is compared or tested
TIGHTNESS_TOLERANCE_M = 0.1  # metres: calibration target for mean Tightness by size
SYMMETRY_MIN_SIZE = 3  # Symmetry is 0 by definition for pairs: tests start at 3
CONFIDENCE_LEVEL = 0.95  # of Tukey's simultaneous confidence intervals
QUANTILES = (0.1, 0.25, 0.5, 0.75, 0.9)  # reported for the pair features


def _readonly(array: np.ndarray) -> np.ndarray:
    array = np.array(array, copy=True)
    array.flags.writeable = False
    return array


# --------------------------------------------------------------------------------------------
# Pair features


class PairSamples(NamedTuple):
    """Pair features and labels of every pair of a set of annotated frames.

    Attributes:
        distance: (n_pairs,) float64 Distance, metres.
        effort_angle: (n_pairs,) float64 Effort Angle, radians in [0, 2*pi].
        label: (n_pairs,) int64, 1 when both are in the same ground-truth F-formation, else 0.
    """

    distance: np.ndarray
    effort_angle: np.ndarray
    label: np.ndarray

    def feature(self, name: str) -> np.ndarray:
        """The samples of one feature (:data:`PAIR_FEATURES`)."""
        if name == DISTANCE:
            return self.distance
        if name == EFFORT_ANGLE:
            return self.effort_angle
        raise ValueError(f"feature must be one of {PAIR_FEATURES}, got {name!r}")

    def select(self, feature: str, kind: str) -> np.ndarray:
        """One feature's samples over the in-group or out-of-group pairs (:data:`PAIR_KINDS`)."""
        if kind not in PAIR_KINDS:
            raise ValueError(f"kind must be one of {PAIR_KINDS}, got {kind!r}")
        values = self.feature(feature)
        return values[self.label == (1 if kind == IN_GROUP else 0)]


def _group_of(frame: Frame) -> np.ndarray:
    """(n,) int64: the index of each row's F-formation, a distinct negative number if alone."""
    n = frame.n_people
    group_of = np.arange(-1, -n - 1, -1, dtype=np.int64)
    row_of = {person: row for row, person in enumerate(frame.ids.tolist())}
    for g, group in enumerate(frame.groups or ()):
        if len(group) >= 2:
            group_of[[row_of[person] for person in group]] = g
    return group_of


def pair_feature_samples(frames: Iterable[Frame]) -> PairSamples:
    """Distance, Effort Angle and label of every pair of the annotated frames.

    Features from :func:`reform.features.batch_pair_features` (body positions and yaws); labels
    as :func:`reform.metrics.pair_labels` gives them. Vectorised over the frames that have the
    same number of people.

    Args:
        frames: frames in any order; frames without ground truth are skipped.

    Returns:
        Read-only arrays, frame by frame, pairs of each frame in
        :func:`reform.features.pair_indices` order.
    """
    annotated = [f for f in frames if f.groups is not None and f.n_people >= 2]
    counts = np.array([f.n_people * (f.n_people - 1) // 2 for f in annotated], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    total = int(starts[-1])
    distance = np.empty(total, dtype=np.float64)
    effort = np.empty(total, dtype=np.float64)
    label = np.empty(total, dtype=np.int64)
    by_people: dict[int, list[int]] = {}
    for k, frame in enumerate(annotated):
        by_people.setdefault(frame.n_people, []).append(k)
    for n, members in by_people.items():
        position = np.stack([annotated[k].position for k in members])
        yaw = np.stack([annotated[k].yaw for k in members])
        group_of = np.stack([_group_of(annotated[k]) for k in members])
        values = batch_pair_features(position, yaw, features=PAIR_FEATURES)
        i, j = pair_indices(n)
        rows = (starts[members][:, None] + np.arange(i.size)[None, :]).ravel()
        distance[rows] = values[..., 0].ravel()
        effort[rows] = values[..., 1].ravel()
        label[rows] = (group_of[:, i] == group_of[:, j]).ravel()
    return PairSamples(_readonly(distance), _readonly(effort), _readonly(label))


# --------------------------------------------------------------------------------------------
# Characterisation by group size


@dataclass(frozen=True)
class SizeStats:
    """Summary of the F-formations of one size.

    Attributes:
        size: number of members.
        count: number of F-formations of this size.
        tightness_mean: metres.
        tightness_std: metres, sample standard deviation (ddof 1); NaN for one group.
        symmetry_mean: degrees.
        symmetry_std: degrees, sample standard deviation (ddof 1); NaN for one group.
    """

    size: int
    count: int
    tightness_mean: float
    tightness_std: float
    symmetry_mean: float
    symmetry_std: float

    def mean(self, measure: str) -> float:
        return self.tightness_mean if _check_measure(measure) == TIGHTNESS else self.symmetry_mean

    def std(self, measure: str) -> float:
        return self.tightness_std if _check_measure(measure) == TIGHTNESS else self.symmetry_std

    def to_json(self) -> dict[str, Any]:
        return json_record(
            self,
            {
                "tightness_mean": "tightness_mean_m",
                "tightness_std": "tightness_std_m",
                "symmetry_mean": "symmetry_mean_deg",
                "symmetry_std": "symmetry_std_deg",
            },
        )


def _check_measure(measure: str) -> str:
    if measure not in MEASURES:
        raise ValueError(f"measure must be one of {MEASURES}, got {measure!r}")
    return measure


def _std(values: np.ndarray) -> float:
    return float(values.std(ddof=1)) if values.size > 1 else math.nan


@dataclass(frozen=True, eq=False)
class Characterisation:
    """What the calibration measures on one dataset.

    Attributes:
        shapes: Tightness and Symmetry of every ground-truth F-formation (the per-group samples).
        pairs: pair features and labels of every pair of the annotated frames.
        frames: number of annotated frames measured.
        name: the dataset's name, for reports.
    """

    shapes: GroupShapes
    pairs: PairSamples
    frames: int
    name: str = ""
    _by_size: Mapping[int, SizeStats] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        by_size = {}
        for size in self.shapes.sizes():
            mask = self.shapes.size == size
            tight = self.shapes.tightness[mask]
            sym = self.shapes.symmetry[mask]
            by_size[size] = SizeStats(
                size=size,
                count=int(mask.sum()),
                tightness_mean=float(tight.mean()),
                tightness_std=_std(tight),
                symmetry_mean=float(sym.mean()),
                symmetry_std=_std(sym),
            )
        object.__setattr__(self, "_by_size", MappingProxyType(by_size))

    def sizes(self) -> tuple[int, ...]:
        """The F-formation sizes present, increasing."""
        return tuple(self._by_size)

    def by_size(self) -> Mapping[int, SizeStats]:
        """``size -> SizeStats``, sizes increasing."""
        return self._by_size

    def count(self, size: int) -> int:
        """Number of F-formations of ``size`` (0 when absent)."""
        stats_ = self._by_size.get(int(size))
        return 0 if stats_ is None else stats_.count

    def mean(self, measure: str, size: int) -> float:
        """Mean of ``measure`` over the F-formations of ``size``; NaN when there are none."""
        _check_measure(measure)
        stats_ = self._by_size.get(int(size))
        return math.nan if stats_ is None else stats_.mean(measure)

    def samples(self, measure: str, size: int) -> np.ndarray:
        """``measure`` of every F-formation of ``size`` (metres or degrees)."""
        values = (
            self.shapes.tightness if _check_measure(measure) == TIGHTNESS else self.shapes.symmetry
        )
        return values[self.shapes.size == int(size)]

    @property
    def fformations(self) -> int:
        """Number of F-formations measured."""
        return int(self.shapes.size.size)

    def pair_summary(self) -> dict[str, dict[str, dict[str, float | int | None]]]:
        """``feature -> kind -> {"n", "mean", "q10", "q25", "median", "q75", "q90"}``."""
        out: dict[str, dict[str, dict[str, float | int | None]]] = {}
        for feature in PAIR_FEATURES:
            out[feature] = {}
            for kind in PAIR_KINDS:
                values = self.pairs.select(feature, kind)
                entry: dict[str, float | int | None] = {"n": int(values.size)}
                if values.size:
                    q = np.quantile(values, QUANTILES)
                    entry.update(
                        mean=float(values.mean()),
                        q10=float(q[0]),
                        q25=float(q[1]),
                        median=float(q[2]),
                        q75=float(q[3]),
                        q90=float(q[4]),
                    )
                else:
                    entry.update(mean=None, q10=None, q25=None, median=None, q75=None, q90=None)
                out[feature][kind] = entry
        return out

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready summary (no per-group or per-pair samples)."""
        return {
            "name": self.name,
            "annotated_frames": self.frames,
            "fformations": self.fformations,
            "pairs": int(self.pairs.label.size),
            "by_size": [s.to_json() for s in self._by_size.values()],
            "pair_features": self.pair_summary(),
        }


def characterise_dataset(
    frames: Iterable[Frame] | Dataset, *, name: str | None = None
) -> Characterisation:
    """Tightness and Symmetry by group size and the pair features of a dataset's annotated frames.

    Robots count as people: a robot in an F-formation is one of its members, and its pairs are
    measured like any other.

    Args:
        frames: a :class:`reform.Dataset` or frames; frames without ground truth are skipped.
        name: name for reports; default the dataset's name (or ``""`` for bare frames).

    Returns:
        The characterisation.
    """
    if name is None:
        name = frames.name if isinstance(frames, Dataset) else ""
    annotated = [f for f in frames if f.groups is not None]
    return Characterisation(
        shapes=characterise(annotated),
        pairs=pair_feature_samples(annotated),
        frames=len(annotated),
        name=name,
    )


# --------------------------------------------------------------------------------------------
# Tests between group sizes


def eligible_sizes(
    characterisation: Characterisation,
    *,
    measure: str = TIGHTNESS,
    min_groups: int = MIN_GROUPS,
) -> tuple[int, ...]:
    """Sizes with at least ``min_groups`` F-formations (and, for Symmetry, at least 3 members)."""
    _check_measure(measure)
    smallest = SYMMETRY_MIN_SIZE if measure == SYMMETRY else 2
    return tuple(
        s
        for s in characterisation.sizes()
        if s >= smallest and characterisation.count(s) >= min_groups
    )


def _test_sizes(
    characterisation: Characterisation, measure: str, sizes: Sequence[int] | None, min_groups: int
) -> tuple[int, ...]:
    if sizes is None:
        chosen = eligible_sizes(characterisation, measure=measure, min_groups=min_groups)
    else:
        chosen = tuple(sorted({int(s) for s in sizes}))
        thin = [s for s in chosen if characterisation.count(s) < 2]
        if thin:
            raise ValueError(
                "sizes must each hold at least 2 F-formations of "
                f"{characterisation.name or 'the data'}, "
                f"got {[(s, characterisation.count(s)) for s in thin]} (size, groups)"
            )
    if len(chosen) < 2:
        raise ValueError(
            f"{measure} by size needs at least two group sizes with >= {min_groups} F-formations, "
            f"got {list(chosen)} (groups by size: "
            f"{ {s: characterisation.count(s) for s in characterisation.sizes()} })"
        )
    return chosen


@dataclass(frozen=True)
class Anova:
    """One-way ANOVA of a measure with group size as the factor (``scipy.stats.f_oneway``).

    Attributes:
        measure: ``"tightness"`` or ``"symmetry"``.
        sizes: the group sizes compared.
        statistic: F.
        pvalue: p.
        df_between: number of sizes - 1.
        df_within: number of F-formations - number of sizes.
    """

    measure: str
    sizes: tuple[int, ...]
    statistic: float
    pvalue: float
    df_between: int
    df_within: int

    def to_json(self) -> dict[str, Any]:
        return json_record(self, {"statistic": "F", "pvalue": "p"})


def anova_by_size(
    characterisation: Characterisation,
    *,
    measure: str = TIGHTNESS,
    sizes: Sequence[int] | None = None,
    min_groups: int = MIN_GROUPS,
) -> Anova:
    """One-way ANOVA of ``measure`` across group sizes.

    Args:
        characterisation: from :func:`characterise_dataset`.
        measure: ``"tightness"`` or ``"symmetry"``.
        sizes: the sizes to compare; default :func:`eligible_sizes`.
        min_groups: fewest F-formations a size needs to be included by default.

    Returns:
        F, p and the degrees of freedom.

    Raises:
        ValueError: fewer than two sizes to compare, or a requested size with under 2 groups.
    """
    _check_measure(measure)
    chosen = _test_sizes(characterisation, measure, sizes, min_groups)
    samples = [characterisation.samples(measure, s) for s in chosen]
    result = stats.f_oneway(*samples)
    total = sum(s.size for s in samples)
    return Anova(
        measure=measure,
        sizes=chosen,
        statistic=float(result.statistic),
        pvalue=float(result.pvalue),
        df_between=len(chosen) - 1,
        df_within=total - len(chosen),
    )


@dataclass(frozen=True)
class TukeyPair:
    """Tukey's HSD for one pair of sizes.

    Attributes:
        size_a: the smaller size.
        size_b: the larger size.
        difference: mean of ``size_b`` minus mean of ``size_a`` (metres or degrees).
        pvalue: adjusted p.
        ci_low: lower end of the simultaneous confidence interval of the difference.
        ci_high: its upper end.
    """

    size_a: int
    size_b: int
    difference: float
    pvalue: float
    ci_low: float
    ci_high: float

    def to_json(self) -> dict[str, Any]:
        return json_record(self, {"pvalue": "p"})


@dataclass(frozen=True)
class Tukey:
    """Tukey's HSD between every pair of group sizes (``scipy.stats.tukey_hsd``).

    Attributes:
        measure: ``"tightness"`` or ``"symmetry"``.
        sizes: the group sizes compared.
        pairs: one entry per pair of sizes, ``(a, b)`` with ``a < b``, in lexicographic order.
        confidence_level: of the intervals.
    """

    measure: str
    sizes: tuple[int, ...]
    pairs: tuple[TukeyPair, ...]
    confidence_level: float

    def pair(self, size_a: int, size_b: int) -> TukeyPair:
        """The entry of two sizes, in either order."""
        a, b = sorted((int(size_a), int(size_b)))
        for entry in self.pairs:
            if (entry.size_a, entry.size_b) == (a, b):
                return entry
        raise KeyError(f"sizes ({a}, {b}) were not compared; sizes are {list(self.sizes)}")

    def to_json(self) -> dict[str, Any]:
        return {
            "measure": self.measure,
            "sizes": list(self.sizes),
            "confidence_level": self.confidence_level,
            "pairs": [p.to_json() for p in self.pairs],
        }


def tukey_by_size(
    characterisation: Characterisation,
    *,
    measure: str = TIGHTNESS,
    sizes: Sequence[int] | None = None,
    min_groups: int = MIN_GROUPS,
    confidence_level: float = CONFIDENCE_LEVEL,
) -> Tukey:
    """Tukey's honestly significant difference test of ``measure`` between group sizes.

    Args:
        characterisation, measure, sizes, min_groups: as for :func:`anova_by_size`.
        confidence_level: of the simultaneous confidence intervals, in (0, 1).

    Returns:
        Every pair of sizes with its mean difference, adjusted p and confidence interval.

    Raises:
        ValueError: as :func:`anova_by_size`, or a confidence level outside (0, 1).
    """
    _check_measure(measure)
    if not 0.0 < confidence_level < 1.0:
        raise ValueError(f"confidence_level must be in (0, 1), got {confidence_level}")
    chosen = _test_sizes(characterisation, measure, sizes, min_groups)
    result = stats.tukey_hsd(*[characterisation.samples(measure, s) for s in chosen])
    interval = result.confidence_interval(confidence_level=confidence_level)
    pairs = []
    for i in range(len(chosen)):
        for j in range(i + 1, len(chosen)):
            # scipy's statistic[i, j] is mean_i - mean_j; report the larger size minus the smaller.
            pairs.append(
                TukeyPair(
                    size_a=chosen[i],
                    size_b=chosen[j],
                    difference=float(-result.statistic[i, j]),
                    pvalue=float(result.pvalue[i, j]),
                    ci_low=float(-interval.high[i, j]),
                    ci_high=float(-interval.low[i, j]),
                )
            )
    return Tukey(
        measure=measure, sizes=chosen, pairs=tuple(pairs), confidence_level=confidence_level
    )


# --------------------------------------------------------------------------------------------
# Candidate against reference


@dataclass(frozen=True)
class KsResult:
    """Two-sample Kolmogorov-Smirnov test of one pair feature (``scipy.stats.ks_2samp``).

    Attributes:
        feature: ``"distance"`` or ``"effort_angle"``.
        kind: ``"in-group"`` or ``"out-of-group"``.
        statistic: largest gap between the two empirical CDFs, in [0, 1]; NaN if a side is empty.
        pvalue: two-sided p; NaN if a side is empty.
        candidate_n: number of candidate pairs.
        reference_n: number of reference pairs.
        candidate_median: metres or radians; NaN if empty.
        reference_median: metres or radians; NaN if empty.
    """

    feature: str
    kind: str
    statistic: float
    pvalue: float
    candidate_n: int
    reference_n: int
    candidate_median: float
    reference_median: float

    def to_json(self) -> dict[str, Any]:
        return {
            "feature": self.feature,
            "kind": self.kind,
            "unit": UNITS[self.feature],
            "statistic": json_float(self.statistic),
            "p": json_float(self.pvalue),
            "candidate_n": self.candidate_n,
            "reference_n": self.reference_n,
            "candidate_median": json_float(self.candidate_median),
            "reference_median": json_float(self.reference_median),
        }


def _ks(feature: str, kind: str, candidate: PairSamples, reference: PairSamples) -> KsResult:
    a = candidate.select(feature, kind)
    b = reference.select(feature, kind)
    if a.size and b.size:
        with warnings.catch_warnings():
            # With many ties the exact small-sample method may fail; scipy then falls back to
            # the asymptotic p-value, which is what we want, without the warning.
            warnings.filterwarnings("ignore", "ks_2samp: Exact calculation", RuntimeWarning)
            result = stats.ks_2samp(a, b)
        statistic, pvalue = float(result.statistic), float(result.pvalue)
    else:
        statistic = pvalue = math.nan
    return KsResult(
        feature=feature,
        kind=kind,
        statistic=statistic,
        pvalue=pvalue,
        candidate_n=int(a.size),
        reference_n=int(b.size),
        candidate_median=float(np.median(a)) if a.size else math.nan,
        reference_median=float(np.median(b)) if b.size else math.nan,
    )


@dataclass(frozen=True, eq=False)
class Comparison:
    """A candidate dataset beside a reference: the numbers the calibration targets.

    Attributes:
        candidate: the candidate's characterisation (e.g. a synthetic scenario).
        reference: the reference's (e.g. SALSA or Babble).
        ks: Kolmogorov-Smirnov results, Distance then Effort Angle, in-group then out-of-group.
    """

    candidate: Characterisation
    reference: Characterisation
    ks: tuple[KsResult, ...]

    def reference_sizes(self, *, min_groups: int = MIN_GROUPS) -> tuple[int, ...]:
        """The reference's sizes with at least ``min_groups`` F-formations: the sizes checked."""
        return tuple(s for s in self.reference.sizes() if self.reference.count(s) >= min_groups)

    def difference(self, measure: str) -> dict[int, float]:
        """``size -> candidate mean - reference mean`` over every reference size (NaN if absent)."""
        return {
            s: self.candidate.mean(measure, s) - self.reference.mean(measure, s)
            for s in self.reference.sizes()
        }

    def tightness_difference(self) -> dict[int, float]:
        """``size -> candidate - reference`` mean Tightness, metres (NaN: candidate lacks it)."""
        return self.difference(TIGHTNESS)

    def symmetry_difference(self) -> dict[int, float]:
        """``size -> candidate - reference`` mean Symmetry, degrees (NaN: candidate lacks it)."""
        return self.difference(SYMMETRY)

    def ks_result(self, feature: str, kind: str) -> KsResult:
        """The Kolmogorov-Smirnov result of one feature and kind of pair."""
        for entry in self.ks:
            if entry.feature == feature and entry.kind == kind:
                return entry
        raise ValueError(
            f"feature must be one of {PAIR_FEATURES} and kind one of {PAIR_KINDS}, "
            f"got {feature!r}, {kind!r}"
        )

    def failures(
        self, tol_m: float = TIGHTNESS_TOLERANCE_M, *, min_groups: int = MIN_GROUPS
    ) -> tuple[str, ...]:
        """Why the candidate misses the Tightness target, one line per size (empty: it meets it).

        A size is checked when the reference holds at least ``min_groups`` F-formations of it;
        the candidate must then hold at least ``min_groups`` too, with a mean Tightness within
        ``tol_m`` metres of the reference's.

        Args:
            tol_m: tolerance, metres, > 0.
            min_groups: fewest F-formations of a size on each side, >= 1.
        """
        if not tol_m > 0.0:
            raise ValueError(f"tol_m must be a positive number of metres, got {tol_m}")
        if min_groups < 1:
            raise ValueError(f"min_groups must be >= 1, got {min_groups}")
        sizes = self.reference_sizes(min_groups=min_groups)
        if not sizes:
            name = f" {self.reference.name}" if self.reference.name else ""
            return (
                f"reference{name} holds no group size with >= {min_groups} F-formations: "
                "nothing to calibrate against",
            )
        out = []
        for s in sizes:
            have = self.candidate.count(s)
            if have < min_groups:
                out.append(f"size {s}: candidate has {have} F-formations, needs >= {min_groups}")
                continue
            diff = self.candidate.mean(TIGHTNESS, s) - self.reference.mean(TIGHTNESS, s)
            if not abs(diff) <= tol_m:
                out.append(
                    f"size {s}: mean Tightness {self.candidate.mean(TIGHTNESS, s):.3f} m vs "
                    f"reference {self.reference.mean(TIGHTNESS, s):.3f} m "
                    f"(difference {diff:+.3f} m, tolerance {tol_m:g} m)"
                )
        return tuple(out)

    def within_tolerance(
        self, tol_m: float = TIGHTNESS_TOLERANCE_M, *, min_groups: int = MIN_GROUPS
    ) -> bool:
        """True when the candidate's mean Tightness is within ``tol_m`` of the reference's for
        every reference size with >= ``min_groups`` F-formations (see :meth:`failures`)."""
        return not self.failures(tol_m, min_groups=min_groups)

    def to_json(
        self, *, tol_m: float = TIGHTNESS_TOLERANCE_M, min_groups: int = MIN_GROUPS
    ) -> dict[str, Any]:
        """A JSON-ready summary, with the tolerance check at ``tol_m`` and ``min_groups``."""
        by_size = []
        for s in self.reference.sizes():
            entry: dict[str, Any] = {
                "size": s,
                "candidate_count": self.candidate.count(s),
                "reference_count": self.reference.count(s),
                "checked": self.reference.count(s) >= min_groups,
            }
            for measure in MEASURES:
                unit = UNITS[measure]
                c, r = self.candidate.mean(measure, s), self.reference.mean(measure, s)
                entry[f"{measure}_candidate_{unit}"] = json_float(c)
                entry[f"{measure}_reference_{unit}"] = json_float(r)
                entry[f"{measure}_difference_{unit}"] = json_float(c - r)
            by_size.append(entry)
        failures = self.failures(tol_m, min_groups=min_groups)
        return {
            "candidate": self.candidate.name,
            "reference": self.reference.name,
            "by_size": by_size,
            "ks": [k.to_json() for k in self.ks],
            "tolerance_m": tol_m,
            "min_groups": min_groups,
            "within_tolerance": not failures,
            "failures": list(failures),
        }


def _as_characterisation(data: Characterisation | Dataset | Iterable[Frame]) -> Characterisation:
    return data if isinstance(data, Characterisation) else characterise_dataset(data)


def compare(
    candidate: Characterisation | Dataset | Iterable[Frame],
    reference: Characterisation | Dataset | Iterable[Frame],
) -> Comparison:
    """A candidate dataset beside a reference, by group size and pair-feature distribution.

    Either side may be given as frames, a :class:`reform.Dataset` or a ready
    :class:`Characterisation` (measure a reference once, compare many candidates with it).

    Args:
        candidate: the dataset to calibrate (e.g. a synthetic scenario's frames).
        reference: the dataset to match (e.g. SALSA or Babble).

    Returns:
        Mean Tightness and Symmetry differences by size, and a Kolmogorov-Smirnov test of
        Distance and Effort Angle for in-group and out-of-group pairs.
    """
    candidate = _as_characterisation(candidate)
    reference = _as_characterisation(reference)
    ks = tuple(
        _ks(feature, kind, candidate.pairs, reference.pairs)
        for feature in PAIR_FEATURES
        for kind in PAIR_KINDS
    )
    return Comparison(candidate=candidate, reference=reference, ks=ks)


# --------------------------------------------------------------------------------------------
# The paper's published numbers


@dataclass(frozen=True)
class PaperAnova:
    """A one-way ANOVA as the paper prints it: ``F(df_between, df_within) = statistic``."""

    df_between: int
    df_within: int
    statistic: float
    pvalue_bound: float  # the paper prints "p < bound"

    def to_json(self) -> dict[str, Any]:
        return json_record(self, {"statistic": "F", "pvalue_bound": "p_below"})


@dataclass(frozen=True)
class PaperCharacterisation:
    """The paper's published characterisation of one dataset.

    Attributes:
        dataset: ``"babble"`` or ``"salsa"``.
        tightness_m: size -> mean Tightness, metres.
        symmetry_deg: size -> mean Symmetry, degrees.
        tightness_anova: the ANOVA the paper prints for Tightness, if any.
        symmetry_anova: the ANOVA the paper prints for Symmetry, if any.
        frames: what the paper says it measured.
        provenance: where the numbers are printed.
    """

    dataset: str
    tightness_m: Mapping[int, float]
    symmetry_deg: Mapping[int, float]
    tightness_anova: PaperAnova | None
    symmetry_anova: PaperAnova | None
    frames: str
    provenance: str

    def mean(self, measure: str, size: int) -> float:
        """The paper's mean of ``measure`` for ``size``; NaN when it gives none."""
        table = self.tightness_m if _check_measure(measure) == TIGHTNESS else self.symmetry_deg
        return float(table.get(int(size), math.nan))

    def to_json(self) -> dict[str, Any]:
        return {
            "dataset": self.dataset,
            "tightness_m": {str(k): v for k, v in self.tightness_m.items()},
            "symmetry_deg": {str(k): v for k, v in self.symmetry_deg.items()},
            "tightness_anova": None
            if self.tightness_anova is None
            else self.tightness_anova.to_json(),
            "symmetry_anova": None
            if self.symmetry_anova is None
            else self.symmetry_anova.to_json(),
            "frames": self.frames,
            "provenance": self.provenance,
        }


_PAPER_SECTION = (
    "Hedayati, Muehlbradt, Szafir, Andrist, REFORM: Recognizing F-formations for Social Robots, "
    "IROS 2020, section 'F-Formation Characteristics'"
)

# Paper text, section "F-Formation Characteristics" (reform-paper.tex): Symmetry means and
# ANOVAs in the two "Symmetry" paragraphs, Tightness means and the one Tightness ANOVA in the
# "Tightness" paragraphs. The paper prints the Tightness ANOVA once, before "For the Babble
# dataset"; F(5, 94) fits Babble's 100 annotation lines, so it is attributed to Babble here.
PAPER_CHARACTERISATION: Mapping[str, PaperCharacterisation] = MappingProxyType(
    {
        "babble": PaperCharacterisation(
            dataset="babble",
            tightness_m=MappingProxyType({2: 0.78, 3: 0.80, 4: 0.83, 5: 0.87, 6: 0.90, 7: 0.95}),
            symmetry_deg=MappingProxyType({3: 234.0, 4: 87.0, 5: 44.0, 6: 42.0, 7: 44.0}),
            tightness_anova=PaperAnova(
                df_between=5, df_within=94, statistic=258.0, pvalue_bound=1e-4
            ),
            symmetry_anova=PaperAnova(
                df_between=4, df_within=94, statistic=47.67, pvalue_bound=1e-4
            ),
            frames="100 frames inspected manually (Symmetry and Tightness)",
            provenance=_PAPER_SECTION,
        ),
        "salsa": PaperCharacterisation(
            dataset="salsa",
            tightness_m=MappingProxyType({2: 0.44, 3: 0.54, 4: 0.61, 5: 0.66, 6: 0.67, 7: 0.93}),
            symmetry_deg=MappingProxyType({3: 50.0, 4: 36.0, 5: 32.0, 6: 32.0, 7: 26.0}),
            tightness_anova=None,
            symmetry_anova=PaperAnova(
                df_between=4, df_within=1639, statistic=171.2, pvalue_bound=1e-4
            ),
            frames=(
                "500 frames inspected (Symmetry); "
                "'100 frames in the Babble and SALSA datasets' (Tightness)"
            ),
            provenance=_PAPER_SECTION,
        ),
    }
)


def paper_characterisation_for(name: str) -> PaperCharacterisation | None:
    """The paper's numbers for a dataset named ``name`` (``"salsa"``, ``"Babble"``, ...), if any."""
    return PAPER_CHARACTERISATION.get(name.strip().lower())

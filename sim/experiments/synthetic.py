"""Synthetic training data for detectors that must work on real people.

The pieces every study that trains on simulation shares (``experiment sim2real``, ``demo``):

* :class:`SyntheticSource`: one scenario's share of a training set (episodes, options, rate,
  the annotation model of :mod:`reform.annotation`, tracker noise calibrated on real data);
* :func:`generate_sources`: generates (or reuses, or extends) every source's episodes with
  :func:`sim.generate.generate_dataset` and reads them back;
* :func:`balance_pairs`: every source cut to the same number of training pairs;
* :func:`calibrate_tracker_noise`: the Gaussian tracker noise whose pair features come closest
  to a real training set's (two-sample Kolmogorov-Smirnov statistics);
* :func:`nearest_neighbour_quantiles` and :func:`joint_distances`: where synthetic and real data
  still differ, measured on training data.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from reform.annotation import AnnotationModel
from reform.atomic import file_kind
from reform.calibration import characterise_dataset, compare
from reform.datasets import read_parquet
from reform.detector import training_pairs
from reform.frame import Frame
from reform.perturb import Perturbation
from reform.seeding import Role, derive_rng
from sim.executor import Executor
from sim.generate import generate_dataset, read_card

__all__ = [
    "JOINT_DISTANCE_EDGES_M",
    "NEIGHBOUR_QUANTILES",
    "POSITION_NOISE_GRID_M",
    "SALSA_RATE_HZ",
    "YAW_NOISE_GRID_RAD",
    "NoiseCalibration",
    "SyntheticSource",
    "balance_pairs",
    "calibrate_tracker_noise",
    "count_pairs",
    "even_subset",
    "generate_sources",
    "joint_distances",
    "nearest_neighbour_quantiles",
]

SALSA_RATE_HZ = 1.0 / 3.0  # Hz: SALSA is annotated every 3 s
SALSA_TRAIN = "salsa-train"  # name of SALSA's training split as a calibration reference
POSITION_NOISE_GRID_M = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3)  # metres, per axis (std)
YAW_NOISE_GRID_RAD = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)  # radians (std)


@dataclass(frozen=True)
class SyntheticSource:
    """One scenario's share of the synthetic training set.

    Attributes:
        scenario: registered scenario name.
        episodes: episodes simulated (each its own seed, see :func:`sim.generate.episode_seed`).
        options: scenario option overrides (none: the scenario's defaults).
        rate: frames written per second, Hz.
        duration: episode length, seconds; None for each episode's natural length.
        tracker_noise: perturb the frames with the tracker noise calibrated on SALSA's training
            split (:func:`calibrate_tracker_noise`).
        annotation: how the annotation records each episode (:mod:`reform.annotation`): None
            (exact), ``"random"`` (one model drawn per episode from
            :data:`reform.annotation.ANNOTATION_RANGES`) or an
            :class:`reform.annotation.AnnotationModel`'s settings as a mapping.
        name: the source's name in results (default: its scenario); two sources of one
            scenario (its defaults and other options, say) need two names.
    """

    scenario: str
    episodes: int
    options: Mapping[str, Any] = field(default_factory=dict)
    rate: float = SALSA_RATE_HZ
    duration: float | None = None
    tracker_noise: bool = False
    annotation: str | Mapping[str, Any] | None = None
    name: str = ""

    def __post_init__(self) -> None:
        if not self.name:
            object.__setattr__(self, "name", self.scenario)
        if isinstance(self.episodes, bool) or not isinstance(self.episodes, int):
            raise ValueError(f"episodes must be an int >= 1, got {self.episodes!r}")
        if self.episodes < 1:
            raise ValueError(f"episodes must be an int >= 1, got {self.episodes}")
        object.__setattr__(self, "options", MappingProxyType(dict(self.options)))
        if isinstance(self.annotation, Mapping):
            AnnotationModel(**dict(self.annotation))  # one clear line for a bad setting
            object.__setattr__(self, "annotation", MappingProxyType(dict(self.annotation)))
        elif self.annotation not in (None, "random"):
            raise ValueError(
                f"annotation must be None, 'random' or a mapping of settings, got "
                f"{self.annotation!r}"
            )

    def _annotation_json(self) -> Any:
        return dict(self.annotation) if isinstance(self.annotation, Mapping) else self.annotation

    def folder(self, seed: int) -> str:
        """Folder name of this source's generated data: scenario, seed and a short hash of
        every parameter that changes the data (episodes excluded: more episodes extend it)."""
        key = json.dumps(
            {
                "scenario": self.scenario,
                "options": dict(self.options),
                "rate": self.rate,
                "duration": self.duration,
                "seed": int(seed),
                **({"annotation": self._annotation_json()} if self.annotation else {}),
            },
            sort_keys=True,
        )
        digest = hashlib.sha256(key.encode()).hexdigest()[:8]
        return f"{self.scenario}-seed{int(seed)}-{digest}"

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "scenario": self.scenario,
            "episodes": self.episodes,
            "options": dict(self.options),
            "rate_hz": self.rate,
            "duration_s": self.duration,
            "tracker_noise": self.tracker_noise,
            "annotation": self._annotation_json(),
        }


def count_pairs(frames: Sequence[Frame]) -> int:
    """Unordered pairs over the frames: sum of n (n - 1) / 2."""
    return int(sum(f.n_people * (f.n_people - 1) // 2 for f in frames))


def _check_synthetic_root(root: Path) -> None:
    """Refuses a synthetic-data folder holding files of its own (a real dataset's, another
    project's): the generated datasets, one folder each, would be written beside them."""
    if not root.is_dir():
        return
    for entry in sorted(root.iterdir()):
        if entry.name.startswith("."):
            continue
        if not entry.is_dir():
            raise ValueError(
                f"{root}: expected a folder of generated datasets (one folder each), found "
                f"{entry.name} ({file_kind(entry)}); give another --synthetic folder"
            )


def even_subset(frames: Sequence[Frame], count: int) -> tuple[Frame, ...]:
    """``count`` frames (at least 1, at most all) at evenly spaced positions of ``frames``, in
    order, so every episode and every stretch of time keeps its share."""
    frames = tuple(frames)
    if count >= len(frames):
        return frames
    positions = np.unique(np.linspace(0, len(frames) - 1, max(1, count)).round().astype(int))
    return tuple(frames[k] for k in positions)


def _episodes_held(folder: Path) -> int:
    """Episodes the generated dataset in ``folder`` holds, by its card (0: no card yet)."""
    card = read_card(folder)
    return int(card.get("episodes") or 0) if card else 0


def generate_sources(
    sources: Sequence[SyntheticSource],
    *,
    root: str | os.PathLike[str],
    seed: int,
    n_jobs: int | None = None,
    progress: bool = True,
    executor: Executor | None = None,
) -> dict[str, tuple[Frame, ...]]:
    """Generates (or reuses) every source's episodes under ``root`` and reads them back.

    Args:
        sources: the sources, each with its own name.
        root: folder holding one generated dataset per source (:meth:`SyntheticSource.folder`).
        seed: master seed of every source.
        n_jobs: worker processes of the generation (default: every core).
        progress: progress bars on stderr.
        executor: where the episodes run (`sim.executor.Executor`), instead of ``n_jobs``
            local processes.

    Returns:
        ``source name -> annotated frames`` (:attr:`SyntheticSource.name`, by default its
        scenario), in the order of ``sources``.
    """
    names = [s.name for s in sources]
    if len(set(names)) != len(names):
        raise ValueError(f"sources must each have their own name, got {names}")
    _check_synthetic_root(Path(root))
    backend = {"n_jobs": n_jobs}
    if executor is not None:
        if n_jobs is not None:
            raise ValueError("n_jobs is for local processes; give it or executor, got both")
        backend = {"n_jobs": executor.jobs, "backend": executor.backend}
        if executor.address is not None:
            backend["address"] = executor.address
    out: dict[str, tuple[Frame, ...]] = {}
    for source in sources:
        folder = Path(root) / source.folder(seed)
        generate_dataset(
            source.scenario,
            episodes=max(source.episodes, _episodes_held(folder)),  # a larger set is reused
            seed=seed,
            out_dir=folder,
            options=dict(source.options),
            rate=source.rate,
            duration=source.duration,
            annotation=source._annotation_json(),
            progress=progress,
            **backend,
        )
        dataset = read_parquet(folder)
        wanted = {f"{source.scenario}-{k}" for k in range(source.episodes)}
        out[source.name] = tuple(f for f in dataset.annotated() if f.sequence in wanted)
    return out


def balance_pairs(
    frames_by_source: Mapping[str, Sequence[Frame]],
) -> dict[str, tuple[Frame, ...]]:
    """Every source cut to (nearly) the pair count of the smallest, by an even subset of frames.

    Frames are kept at evenly spaced positions of each source's frame list (episodes, then
    time), so every episode and every stretch of time keeps its share.

    Returns:
        ``source -> kept frames``, in the input's order.
    """
    counts = {name: count_pairs(frames) for name, frames in frames_by_source.items()}
    if not counts or min(counts.values()) == 0:
        raise ValueError(f"every source needs frames with pairs, got pair counts {counts}")
    target = min(counts.values())
    out: dict[str, tuple[Frame, ...]] = {}
    for name, frames in frames_by_source.items():
        frames = tuple(frames)
        if counts[name] <= target:
            out[name] = frames
            continue
        out[name] = even_subset(frames, round(len(frames) * target / counts[name]))
    return out


# ------------------------------------------------------------------------------------------
# Tracker noise


@dataclass(frozen=True)
class NoiseCalibration:
    """The tracker noise that brings synthetic pair features closest to a reference's.

    Attributes:
        position_noise: chosen standard deviation per position axis, metres.
        yaw_noise: chosen standard deviation of yaw, radians.
        reference: the reference's name (``"salsa-train"``).
        grid: per grid point ``(position_noise, yaw_noise, ks)``, ``ks`` the four KS statistics
            (Distance in-group, out-of-group, Effort Angle in-group, out-of-group).
    """

    position_noise: float
    yaw_noise: float
    reference: str
    grid: tuple[tuple[float, float, tuple[float, float, float, float]], ...]

    @property
    def objective(self) -> float:
        """Sum of the four KS statistics at the chosen point."""
        return self.ks_at(self.position_noise, self.yaw_noise)[1]

    def ks_at(self, position_noise: float, yaw_noise: float) -> tuple[tuple[float, ...], float]:
        """The KS statistics and their sum at one grid point."""
        for p, y, ks in self.grid:
            if p == position_noise and y == yaw_noise:
                return ks, float(sum(ks))
        raise ValueError(f"({position_noise}, {yaw_noise}) is not on the calibration grid")

    def perturbation(self) -> Any:
        return Perturbation(position_noise=self.position_noise, yaw_noise=self.yaw_noise)

    def to_json(self) -> dict[str, Any]:
        return {
            "reference": self.reference,
            "objective": "sum of the KS statistics of Distance and Effort Angle, in-group and "
            "out-of-group pairs (reform.calibration.compare)",
            "position_noise_m": self.position_noise,
            "yaw_noise_rad": self.yaw_noise,
            "ks_sum": self.objective,
            "grid": [
                {
                    "position_noise_m": p,
                    "yaw_noise_rad": y,
                    "ks": list(ks),
                    "ks_sum": float(sum(ks)),
                }
                for p, y, ks in self.grid
            ],
        }


def calibrate_tracker_noise(
    frames: Sequence[Frame],
    reference: Sequence[Frame],
    *,
    seed: int,
    reference_name: str = SALSA_TRAIN,
    position_grid: Sequence[float] = POSITION_NOISE_GRID_M,
    yaw_grid: Sequence[float] = YAW_NOISE_GRID_RAD,
) -> NoiseCalibration:
    """Chooses the tracker noise whose perturbed frames match the reference's pair features best.

    Every grid point perturbs the same frames with the same standard normals (the common random
    numbers of :class:`reform.perturb.Perturbation`, generator seeded with ``seed``), measures
    :func:`reform.calibration.compare` against the reference and sums the four KS statistics;
    the smallest sum wins (ties: the smaller noise, first position then yaw).

    Args:
        frames: synthetic annotated frames.
        reference: real annotated frames (training data only).
        seed: seed of the noise draws.
        reference_name: the reference's name in the result.
        position_grid: position noise levels tried, metres.
        yaw_grid: yaw noise levels tried, radians.
    """
    if not frames or not reference:
        raise ValueError(
            f"calibration needs synthetic and reference frames, got {len(frames)} and "
            f"{len(reference)}"
        )
    target = characterise_dataset(reference)
    grid = []
    for p in sorted(float(v) for v in position_grid):
        for y in sorted(float(v) for v in yaw_grid):
            noisy = Perturbation(position_noise=p, yaw_noise=y).apply_all(
                frames, derive_rng(seed, Role.TRACKER_NOISE_FIT)
            )
            ks = tuple(float(k.statistic) for k in compare(noisy, target).ks)
            grid.append((p, y, ks))
    best = min(grid, key=lambda entry: (round(sum(entry[2]), 12), entry[0], entry[1]))
    return NoiseCalibration(
        position_noise=best[0], yaw_noise=best[1], reference=reference_name, grid=tuple(grid)
    )


# ------------------------------------------------------------------------------------------
# Where synthetic and real data differ


JOINT_DISTANCE_EDGES_M = (0.0, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0, 4.0, math.inf)
JOINT_EFFORT_BINS = 8  # Effort Angle bins over [0, 2 pi]
NEIGHBOUR_QUANTILES = (0.1, 0.25, 0.5)


def nearest_neighbour_quantiles(frames: Sequence[Frame]) -> tuple[float, ...]:
    """Quantiles (:data:`NEIGHBOUR_QUANTILES`) of every person's distance to the nearest other
    person in the same frame, metres."""
    nearest = []
    for frame in frames:
        if frame.n_people < 2:
            continue
        p = frame.position
        d = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
        np.fill_diagonal(d, np.inf)
        nearest.append(d.min(axis=1))
    if not nearest:
        raise ValueError("frames must hold at least one frame of two or more people")
    return tuple(float(q) for q in np.quantile(np.concatenate(nearest), NEIGHBOUR_QUANTILES))


def joint_distances(frames: Sequence[Frame], reference: Sequence[Frame]) -> tuple[float, float]:
    """Total-variation distance between the joint (Distance, Effort Angle) histograms of two
    datasets' pairs: in-group pairs, then out-of-group pairs (0: same shares in every bin, 1:
    disjoint). The marginals compared by KS can agree while the joint, which a pair classifier
    learns, does not."""
    edges = (
        np.asarray(JOINT_DISTANCE_EDGES_M),
        np.linspace(0.0, 2.0 * math.pi, JOINT_EFFORT_BINS + 1),
    )

    def shares(x: np.ndarray, y: np.ndarray, label: int) -> np.ndarray:
        h, _, _ = np.histogram2d(x[y == label, 0], x[y == label, 1], bins=edges)
        return h / max(h.sum(), 1.0)

    xa, ya, _ = training_pairs(frames)
    xb, yb, _ = training_pairs(reference)
    return tuple(  # type: ignore[return-value]
        float(0.5 * np.abs(shares(xa, ya, label) - shares(xb, yb, label)).sum()) for label in (1, 0)
    )

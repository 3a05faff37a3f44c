"""Annotation models: what turns a simulated world into a dataset like a real one.

A simulator knows every pose exactly and every group the moment its rule settles it. The
field's datasets do not: their orientations are coded in a few directions (4 in some, 24 in
others) or come continuous from motion capture; some record the head's orientation as the
person's; positions estimated from video carry a scale error of their own and a tracker's
jitter and dropouts; and annotators call a group only once it has lasted. An `AnnotationModel`
is that layer, named and seeded, applied to the ground-truth frames of one episode
(`AnnotationModel.apply`); `sim.generate` records it in the dataset card.

The steps, in this order, each a no-op at its default:

1. **orientation source** (``orientation="head"``): each person's yaw becomes their head's yaw
   where the head is observed (the body's elsewhere);
2. **scale** (``scale``, ``scale_sd``): every position (body and head) is multiplied by the
   fixed factor ``scale`` (a dataset's unit or calibration, as a venue twin fits it) and by one
   factor ``1 + e``, ``e ~ N(0, scale_sd)`` drawn once per episode (and kept above 0.5), as a
   camera calibration's error scales a whole recording;
3. **tracker** (``position_noise``, ``yaw_noise``, ``dropout``): `reform.TrackerNoise` on every
   frame (robots kept exact, as everywhere);
4. **coding** (``directions=k``): every yaw (body and head) is rounded to the nearest of ``k``
   directions ``2 pi j / k`` (``None``: continuous), as an annotator codes what they saw;
5. **the annotator's rule** (``min_group_seconds``): a group (the same members) annotated for
   less than this long in a row is not called a group: its members stand alone in those frames.

Random numbers: the scale factor first (one normal), then the tracker's draws frame by frame,
all from the generator given (`reform.seeding` gives each episode its own).

`ANNOTATION_RANGES` documents the ranges `draw_annotation` draws from when a dataset's
annotation is randomised (one model per episode), spanning the public datasets.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, fields
from types import MappingProxyType
from typing import Any

import numpy as np

from reform._checks import check_levels
from reform.frame import Frame, Group, wrap_angle
from reform.perturb import TrackerNoise

__all__ = [
    "ANNOTATION_RANGES",
    "MAX_DIRECTIONS",
    "MAX_POSITION_NOISE_M",
    "MAX_SCALE",
    "MAX_SCALE_SD",
    "MAX_YAW_NOISE_RAD",
    "ORIENTATIONS",
    "AnnotationModel",
    "draw_annotation",
    "parse_annotation",
]

ORIENTATIONS = ("body", "head")  # what a dataset records as a person's orientation
MIN_SCALE = 0.5  # a scale factor is kept at or above this (a drawn error never flips a scene)
# The largest settings a model takes: beyond them the recorded positions leave what a frame
# holds (`reform.Frame`: |x|, |y| <= 1e8), or the model is not an annotation of the scene.
MAX_SCALE = 1e4  # a length unit of at least 0.1 mm
MAX_SCALE_SD = 1.0  # a scale error of 100 %
MAX_POSITION_NOISE_M = 10.0  # metres: jitter larger than any room's people
MAX_YAW_NOISE_RAD = 2.0 * math.pi  # a full turn: beyond it the recorded yaw is as random
MAX_DIRECTIONS = 3600  # a tenth of a degree: finer coding is continuous for any detector

# The ranges a randomised annotation draws from, one model per episode: each a tuple of
# choices, or (low, high) for a uniform draw. They span the field's public datasets:
# orientation coded in 4 (Cocktail Party), 8, 24 (Idiap Poster) directions or continuous (SALSA,
# Babble's motion capture); head or body orientation; video-estimated positions (scale errors of
# a few per cent, tracker jitter of a few centimetres, a few per cent of people missed);
# annotators who call a group after 0-3 s.
ANNOTATION_RANGES: Mapping[str, tuple[Any, ...]] = MappingProxyType(
    {
        "orientation": ("body", "head"),
        "directions": (None, 4, 8, 24),
        "scale_sd": (0.0, 0.05),
        "position_noise": (0.0, 0.1),
        "yaw_noise": (0.0, 0.3),
        "dropout": (0.0, 0.05),
        "min_group_seconds": (0.0, 3.0),
    }
)
_CHOICES = ("orientation", "directions")  # drawn from a list; the others uniformly


@dataclass(frozen=True)
class AnnotationModel:
    """How one dataset's annotation records a scene (see the module docstring for the steps).

    Attributes:
        orientation: ``"body"`` or ``"head"``: the orientation recorded as each person's yaw.
        directions: the number of directions orientations are coded in (1 to
            `MAX_DIRECTIONS`), or None for continuous orientations.
        scale_sd: standard deviation of the episode's scale error, a fraction (0 to
            `MAX_SCALE_SD`).
        position_noise: tracker jitter on each position coordinate, metres (0 to
            `MAX_POSITION_NOISE_M`).
        yaw_noise: tracker jitter on each yaw, radians (0 to `MAX_YAW_NOISE_RAD`).
        dropout: probability that the tracker misses a person in a frame, in [0, 1).
        min_group_seconds: the shortest run, seconds, for which annotators call a group (>= 0).
        scale: a fixed factor every position is multiplied by (> 0, at most `MAX_SCALE`): the
            dataset's length unit or calibration against the simulated metres (1: none).
    """

    orientation: str = "body"
    directions: int | None = None
    scale_sd: float = 0.0
    position_noise: float = 0.0
    yaw_noise: float = 0.0
    dropout: float = 0.0
    min_group_seconds: float = 0.0
    scale: float = 1.0

    def __post_init__(self) -> None:
        if self.orientation not in ORIENTATIONS:
            raise ValueError(
                f"annotation orientation must be one of {list(ORIENTATIONS)}, got "
                f"{self.orientation!r}"
            )
        k = self.directions
        if k is not None:
            if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
                raise ValueError(
                    f"annotation directions must be a whole number >= 1 (or continuous), got {k!r}"
                )
            if k > MAX_DIRECTIONS:
                raise ValueError(
                    f"annotation directions must be at most {MAX_DIRECTIONS} (finer is "
                    f"continuous: leave it out), got {k!r}"
                )
            object.__setattr__(self, "directions", int(k))
        levels = ("scale_sd", "position_noise", "yaw_noise", "min_group_seconds")
        check_levels(self, "annotation ", levels, probabilities=("dropout",))
        if self.dropout >= 1.0:
            raise ValueError(
                f"annotation dropout must be below 1 (1 drops everyone from every frame), got "
                f"{self.dropout!r}"
            )
        for name, high in (
            ("scale_sd", MAX_SCALE_SD),
            ("position_noise", MAX_POSITION_NOISE_M),
            ("yaw_noise", MAX_YAW_NOISE_RAD),
        ):
            if getattr(self, name) > high:
                raise ValueError(
                    f"annotation {name} must be at most {high:g}, got {getattr(self, name)!r}"
                )
        scale = self.scale
        if isinstance(scale, bool) or not isinstance(scale, (int, float, np.number)):
            raise ValueError(f"annotation scale must be a finite number > 0, got {scale!r}")
        if not math.isfinite(float(scale)) or not 0.0 < float(scale) <= MAX_SCALE:
            raise ValueError(
                f"annotation scale must be a finite number > 0 and at most {MAX_SCALE:g}, got "
                f"{scale!r}"
            )
        object.__setattr__(self, "scale", float(scale))

    @property
    def identity(self) -> bool:
        """Whether the model leaves frames as they are."""
        return self == AnnotationModel()

    def to_json(self) -> dict[str, Any]:
        """The settings as JSON values; ``scale`` only when it is not 1 (so that the cards of
        datasets annotated before it existed stay as they were)."""
        out = asdict(self)
        if out["scale"] == 1.0:
            del out["scale"]
        return out

    def apply(self, frames: Sequence[Frame], rng: np.random.Generator) -> tuple[Frame, ...]:
        """One episode's frames (in time order) as this annotation records them.

        The frames given are not modified; ``rng`` draws the scale error, then the tracker's
        errors frame by frame (nothing when the model is the identity).
        """
        frames = tuple(frames)
        if self.identity:
            return frames
        scale = self.scale
        if self.scale_sd:
            scale *= max(MIN_SCALE, 1.0 + self.scale_sd * float(rng.normal()))
        tracker = TrackerNoise(self.position_noise, self.yaw_noise, self.dropout)
        noisy = tracker != TrackerNoise()
        out = []
        for frame in frames:
            frame = self._source_and_scale(frame, scale)
            if noisy:
                frame = tracker.apply(frame, rng)
            out.append(self._coded(frame))
        if self.min_group_seconds > 0.0:
            out = _annotator(out, self.min_group_seconds)
        return tuple(out)

    def _source_and_scale(self, frame: Frame, scale: float) -> Frame:
        changes: dict[str, Any] = {}
        if self.orientation == "head" and frame.head_yaw is not None:
            changes["yaw"] = np.where(np.isnan(frame.head_yaw), frame.yaw, frame.head_yaw)
        if scale != 1.0:
            changes["position"] = frame.position * scale
            if frame.head_position is not None:
                changes["head_position"] = frame.head_position * scale
        return frame.replace(**changes) if changes else frame

    def _coded(self, frame: Frame) -> Frame:
        if self.directions is None:
            return frame
        changes: dict[str, Any] = {"yaw": _coded(frame.yaw, self.directions)}
        if frame.head_yaw is not None:
            changes["head_yaw"] = _coded(frame.head_yaw, self.directions)
        return frame.replace(**changes)


def _coded(yaw: np.ndarray, k: int) -> np.ndarray:
    """Yaws rounded to the nearest of ``k`` directions ``2 pi j / k``, wrapped (NaN kept)."""
    step = 2.0 * math.pi / k
    return wrap_angle(np.round(np.asarray(yaw, dtype=np.float64) / step) * step)


def _annotator(frames: list[Frame], min_seconds: float) -> list[Frame]:
    """Groups annotated for less than ``min_seconds`` in a row become people alone."""
    short: dict[int, set[frozenset[int]]] = {}  # frame -> its groups that were too short
    open_runs: dict[frozenset[int], list[int]] = {}  # group -> frames of its current run

    def close(group: frozenset[int], run: list[int]) -> None:
        if frames[run[-1]].time - frames[run[0]].time < min_seconds:
            for k in run:
                short.setdefault(k, set()).add(group)

    for k, frame in enumerate(frames):
        now = {frozenset(g) for g in frame.groups or () if len(g) > 1}
        for group in list(open_runs):
            if group not in now:
                close(group, open_runs.pop(group))
        for group in now:
            open_runs.setdefault(group, []).append(k)
    for group, run in open_runs.items():
        close(group, run)
    out = []
    for k, frame in enumerate(frames):
        dropped = short.get(k)
        if not dropped:
            out.append(frame)
            continue
        groups: list[Group] = []
        for g in frame.groups or ():
            if frozenset(g) in dropped:
                groups.extend((m,) for m in g)
            else:
                groups.append(g)
        out.append(frame.replace(groups=tuple(groups)))
    return out


def draw_annotation(
    rng: np.random.Generator, ranges: Mapping[str, tuple[Any, ...]] = ANNOTATION_RANGES
) -> AnnotationModel:
    """One annotation model drawn from ``ranges`` (default `ANNOTATION_RANGES`): the choices of
    ``orientation`` and ``directions`` uniformly, every other setting uniform on (low, high);
    a setting ``ranges`` does not name keeps its default (``scale``, by default)."""
    values: dict[str, Any] = {}
    for f in fields(AnnotationModel):
        if f.name not in ranges:
            continue
        span = ranges[f.name]
        if f.name in _CHOICES:
            values[f.name] = span[int(rng.integers(len(span)))]
        else:
            low, high = span
            values[f.name] = float(rng.uniform(low, high))
    return AnnotationModel(**values)


def parse_annotation(items: Sequence[str]) -> AnnotationModel:
    """An annotation model from ``KEY=VALUE`` strings (the command line's ``--annotation``).

    Raises:
        ValueError: one line naming the setting, what it must be and what came.
    """
    known = {f.name: f for f in fields(AnnotationModel)}
    values: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or key not in known:
            raise ValueError(
                f"annotation setting {item!r}: expected KEY=VALUE with KEY one of {list(known)}"
            )
        if key == "orientation":
            values[key] = text.strip()
            continue
        if key == "directions" and text.strip().lower() in ("continuous", "none"):
            values[key] = None
            continue
        try:
            number = float(text)
        except ValueError:
            raise ValueError(f"annotation {key} must be a number, got {text!r}") from None
        if key == "directions":
            if not number.is_integer():
                raise ValueError(
                    f"annotation directions must be a whole number >= 1 (or continuous), got "
                    f"{text!r}"
                )
            number = int(number)
        values[key] = number
    return AnnotationModel(**values)

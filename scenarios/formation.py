"""Geometry of an F-formation: members on an o-space circle, facing its centre.

Tightness (the mean distance of the members to their mean position) of people spread evenly on
a circle is the circle's radius, so a scenario's radius law by group size is what sets the
Tightness by size it produces. `RadiusLaw` is linear in the number of members,
``radius(n) = base + per_member * (n - 2)``, never tighter than people's bodies allow
(`min_radius`: neighbours on the circle at least `scenarios.stage.SPACING_M` apart).
`CircleNoise` places members on a circle with noise; `CircleShape` draws a scenario's circles
from its options: the law, the spread of radii about it and that noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from scenarios.stage import SPACING_M

__all__ = [
    "CIRCLE_OPTIONS",
    "CircleNoise",
    "CircleShape",
    "RadiusLaw",
    "ellipse_offsets",
    "facing_centre",
    "min_radius",
    "separate",
    "spread_angles",
]


def min_radius(n: int, *, spacing: float = SPACING_M) -> float:
    """Smallest o-space radius with ``n`` members evenly spread ``spacing`` metres apart."""
    if n < 2:
        raise ValueError(f"n must be >= 2 members, got {n}")
    return spacing / (2.0 * math.sin(math.pi / n))


@dataclass(frozen=True)
class RadiusLaw:
    """O-space radius by group size: ``base + per_member * (n - 2)`` metres, at least
    `min_radius` (n).

    Attributes:
        base: radius of a pair, metres (half the distance between the two).
        per_member: growth per extra member, metres.
        spacing: closest two evenly spread members may stand, metres (`min_radius`).
    """

    base: float
    per_member: float
    spacing: float = SPACING_M

    def __post_init__(self) -> None:
        for name in ("base", "per_member"):
            value = float(getattr(self, name))
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"RadiusLaw.{name} must be >= 0 metres, got {value}")
            object.__setattr__(self, name, value)

    def __call__(self, n: int) -> float:
        return max(self.base + self.per_member * (n - 2), min_radius(n, spacing=self.spacing))


CIRCLE_OPTIONS = MappingProxyType(
    {
        "radius_base": "o-space radius of a pair, metres.",
        "radius_per_member": "growth of the radius per extra member, metres.",
        "radius_spread": "relative standard deviation of a group's radius.",
        "position_noise": "standard deviation of a place, metres.",
        "orientation_noise": "standard deviation of a facing, radians.",
        "head_noise": "standard deviation of a gaze off its target, radians.",
    }
)
"""The help of the options that shape a scenario's circles (`CircleShape`) and the noise of its
members' gaze, for the scenarios that declare them (``word-improv``, ``mingle``), each with its
own range and default (`scenarios.registry.shared_help` writes them into their docstrings)."""


@dataclass(frozen=True)
class CircleNoise:
    """The noise on members' places on an o-space circle and on the way they face its centre.

    Attributes:
        position: standard deviation of a place's offset per axis, metres.
        orientation: standard deviation of a facing's deviation from the centre, radians.
        spacing: closest two places may come after the noise, metres (`separate`).
    """

    position: float = 0.0
    orientation: float = 0.0
    spacing: float = SPACING_M

    def places(
        self,
        centre: np.ndarray,
        radius: float,
        angles: np.ndarray,
        rng: np.random.Generator,
        *,
        aspect: float = 1.0,
        axis: float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Places on an o-space circle and the way each member faces, with this noise.

        Args:
            centre: (2,) metres.
            radius: metres.
            angles: (k,) angle of each member around the centre, radians.
            rng: draws the noise.
            aspect: the o-space's long axis over its short one: 1, a circle; above, an ellipse
                of axes ``radius * sqrt(aspect)`` and ``radius / sqrt(aspect)`` (members still
                face its centre).
            axis: direction of the long axis, radians.

        Returns:
            (places (k, 2) metres, facings (k,) radians).
        """
        angles = np.asarray(angles, dtype=np.float64)
        k = angles.size
        offsets = radius * ellipse_offsets(angles, aspect, axis)
        places = np.asarray(centre, dtype=np.float64) + offsets
        places = places + rng.normal(0.0, 1.0, size=(k, 2)) * self.position
        places = separate(places, spacing=self.spacing)
        facings = facing_centre(places, centre) + rng.normal(0.0, 1.0, size=k) * self.orientation
        facings = np.angle(np.exp(1j * facings))
        return places, facings


@dataclass(frozen=True)
class CircleShape:
    """How a scenario draws its groups' circles: the radius law, the spread of radii about it
    and the noise of places and facings (the options of `CIRCLE_OPTIONS`).

    Attributes:
        law: o-space radius by group size, of the options ``radius_base`` and
            ``radius_per_member``.
        radius_spread: the option of this name.
        noise: of the options ``position_noise`` and ``orientation_noise``.
    """

    law: RadiusLaw
    radius_spread: float = 0.0
    noise: CircleNoise = CircleNoise()

    def radius(self, n: int, rng: np.random.Generator, *, least: float) -> float:
        """The o-space radius of a group of ``n``, metres: the law's times ``1 + spread Z`` (Z
        drawn standard normal), that factor at least ``least``."""
        return self.law(n) * max(1.0 + rng.normal() * self.radius_spread, least)


def spread_angles(n: int, rng: np.random.Generator, *, jitter: float = 0.0) -> np.ndarray:
    """(n,) angles (radians, increasing) of ``n`` members evenly around a circle, rotated at
    random, each moved by uniform noise of up to ``jitter`` of the even gap."""
    start = rng.uniform(-math.pi, math.pi)
    gap = 2.0 * math.pi / n
    noise = rng.uniform(-jitter, jitter, size=n) * gap if jitter > 0.0 else np.zeros(n)
    return start + gap * np.arange(n) + noise


def facing_centre(places: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(k,) yaws (radians) from each place toward ``centre``."""
    d = np.asarray(centre, dtype=np.float64) - np.asarray(places, dtype=np.float64)
    return np.arctan2(d[:, 1], d[:, 0])


def ellipse_offsets(angles: np.ndarray, aspect: float = 1.0, axis: float = 0.0) -> np.ndarray:
    """(k, 2) points at parameter ``angles`` (radians) of an ellipse of mean radius 1 (axes
    ``sqrt(aspect)`` and ``1 / sqrt(aspect)``, the long one toward ``axis``)."""
    angles = np.asarray(angles, dtype=np.float64)
    if aspect == 1.0:
        x, y = np.cos(angles), np.sin(angles)
    else:
        long, short = math.sqrt(aspect), 1.0 / math.sqrt(aspect)
        u, v = long * np.cos(angles - axis), short * np.sin(angles - axis)
        c, s = math.cos(axis), math.sin(axis)
        x, y = c * u - s * v, s * u + c * v
    if angles.ndim != 1:
        return np.stack([x, y], axis=1)
    out = np.empty((angles.size, 2))  # np.stack's array, with less overhead
    out[:, 0] = x
    out[:, 1] = y
    return out


def separate(places: np.ndarray, *, spacing: float = SPACING_M, iterations: int = 20) -> np.ndarray:
    """``places`` (k, 2) moved apart, symmetrically, until no two are closer than ``spacing``
    metres (or ``iterations`` passes are done); places far enough apart do not move."""
    out = np.array(places, dtype=np.float64)
    k = out.shape[0]
    # Pairs whose squared distance clears spacing² by more than rounding can are far enough
    # apart without the exact distance (np.hypot, as always where it decides). The places are
    # moved as Python floats: the same differences, quotients and products as on the array.
    clear = spacing * spacing * (1.0 + 1e-9)
    points = out.tolist()
    hypot = np.hypot
    changed = False
    for _ in range(iterations):
        moved = False
        for i in range(k):
            xi, yi = points[i]
            for j in range(i + 1, k):
                xj, yj = points[j]
                dx, dy = xj - xi, yj - yi
                if dx * dx + dy * dy > clear:
                    continue
                dist = float(hypot(dx, dy))
                if dist >= spacing:
                    continue
                ux, uy = (dx / dist, dy / dist) if dist > 1e-9 else (1.0, 0.0)
                push = 0.5 * (spacing - dist) + 1e-6
                px, py = ux * push, uy * push
                xi, yi = xi - px, yi - py
                points[i], points[j] = [xi, yi], [xj + px, yj + py]
                moved = True
        if not moved:
            break
        changed = True
    return np.array(points, dtype=np.float64) if changed else out

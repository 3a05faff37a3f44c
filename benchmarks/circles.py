"""Synthetic conversational circles: people spaced round a centre, facing it, with noise.

Shared by the benchmark scripts that time detectors on synthetic scenes (``bench_gcff``,
``bench_reform``); each picks its own radius and noise. Imported as ``from circles import ...``
(``benchmarks/`` is first on ``sys.path`` when a script runs).
"""

from __future__ import annotations

import math

import numpy as np


def circle(
    rng: np.random.Generator,
    *,
    centre: np.ndarray,
    size: int,
    radius: float,
    angle_sd: float,
    position_sd: float,
    yaw_sd: float,
) -> tuple[list[np.ndarray], list[float]]:
    """``size`` people evenly spaced round ``centre`` from a random phase, facing it.

    A lone person (``size`` 1) faces a uniformly random direction instead. Draws from ``rng``
    in a fixed order (phase, then per person: angle, position, facing, and the lone yaw), so a
    seed gives the same circle.

    Args:
        rng: Source of every random draw.
        centre: Centre of the circle, metres; shape (2,).
        size: Number of people, at least 1.
        radius: Distance of each person from the centre, metres.
        angle_sd: Standard deviation of each person's angle round the circle, radians.
        position_sd: Standard deviation of each position coordinate, metres.
        yaw_sd: Standard deviation of each facing direction, radians.

    Returns:
        The positions (each shape (2,), metres) and yaws (radians, not wrapped).
    """
    position, yaw = [], []
    phase = rng.uniform(0.0, 2.0 * math.pi)
    for m in range(size):
        a = phase + 2.0 * math.pi * m / size + rng.normal(0.0, angle_sd)
        p = centre + radius * np.array([math.cos(a), math.sin(a)]) + rng.normal(0.0, position_sd, 2)
        facing = math.atan2(*(centre - p)[::-1]) + rng.normal(0.0, yaw_sd)
        position.append(p)
        yaw.append(facing if size > 1 else rng.uniform(-math.pi, math.pi))
    return position, yaw


def wrap_yaws(yaw: list[float]) -> np.ndarray:
    """Yaws wrapped into [-pi, pi), radians; shape (people,)."""
    return (np.asarray(yaw) + math.pi) % (2.0 * math.pi) - math.pi

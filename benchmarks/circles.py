"""Synthetic conversational circles: people spaced round a centre, facing it, with noise.

Shared by the benchmark scripts that time detectors on synthetic scenes (``bench_gcff``,
``bench_reform``): :func:`crowd` fills a scene with circles, each script picking how big a
circle is, where it stands, its radius and its noise. Imported as ``from circles import ...``
(``benchmarks/`` is first on ``sys.path`` when a script runs).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

BASE_RADIUS_M = 0.45  # metres: a circle's radius before its per-person share


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


def crowd(
    rng: np.random.Generator,
    n: int,
    *,
    draw_size: Callable[[], int],
    centre: Callable[[int], np.ndarray],
    radius_per_person_m: float,
    angle_sd: float,
    position_sd: float,
    yaw_sd: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``n`` people in circles (see :func:`circle`), one circle after another until all stand.

    Circle ``k`` (from 0) has ``draw_size()`` people, the last one cut to the people left,
    round ``centre(k)``, at ``BASE_RADIUS_M + radius_per_person_m * size`` from it. Per circle
    the draws come in a fixed order (its size, its centre, then :func:`circle`'s), so a seed
    gives the same scene.

    Args:
        rng: Source of :func:`circle`'s draws (``draw_size`` and ``centre`` draw from it too
            when they are random).
        n: Number of people, at least 1.
        draw_size: The next circle's number of people, at least 1.
        centre: Centre of circle ``k``, metres; shape (2,).
        radius_per_person_m: A circle's radius grows by this per member, metres.
        angle_sd: See :func:`circle`.
        position_sd: See :func:`circle`.
        yaw_sd: See :func:`circle`.

    Returns:
        Positions, metres, shape (n, 2), and yaws wrapped into [-pi, pi), radians, shape (n,).
    """
    position, yaw = [], []
    k = 0
    while len(position) < n:
        size = int(min(draw_size(), n - len(position)))
        members, facing = circle(
            rng,
            centre=centre(k),
            size=size,
            radius=BASE_RADIUS_M + radius_per_person_m * size,
            angle_sd=angle_sd,
            position_sd=position_sd,
            yaw_sd=yaw_sd,
        )
        k += 1
        position += members
        yaw += facing
    return np.asarray(position), wrap_yaws(yaw)

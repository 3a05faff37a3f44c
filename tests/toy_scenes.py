"""Small synthetic scenes for REFORM's tests: circles of people facing their centre, and loners.

Not a simulator (see ``sim/`` and ``scenarios/``): just enough structure for a classifier to learn
from in a fraction of a second.
"""

from __future__ import annotations

import numpy as np

from reform import Frame

GROUP_RADIUS_M = 0.6  # metres, centre to member
SPACING_M = 3.0  # metres between group centres
POSITION_NOISE_M = 0.08  # metres
YAW_NOISE_RAD = 0.25  # radians


def toy_frame(
    rng: np.random.Generator,
    *,
    sizes: tuple[int, ...] = (3, 2, 4),
    loners: int = 2,
    time: float = 0.0,
    sequence: str = "toy",
    first_id: int = 1,
) -> Frame:
    """A frame with one circular F-formation per entry of ``sizes`` and ``loners`` singletons."""
    positions, yaws, groups = [], [], []
    person = first_id
    n_spots = len(sizes) + loners
    side = int(np.ceil(np.sqrt(n_spots)))
    spots = rng.permutation(side * side)[:n_spots]
    centres = np.stack([spots % side, spots // side], axis=1) * SPACING_M
    for centre, size in zip(centres[: len(sizes)], sizes, strict=True):
        angles = rng.uniform(0, 2 * np.pi) + np.arange(size) * 2 * np.pi / size
        ring = centre + GROUP_RADIUS_M * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        positions.append(ring + rng.normal(0, POSITION_NOISE_M, ring.shape))
        yaws.append(angles + np.pi + rng.normal(0, YAW_NOISE_RAD, size))
        groups.append(tuple(range(person, person + size)))
        person += size
    for centre in centres[len(sizes) :]:
        positions.append(centre[None] + rng.normal(0, 0.3, (1, 2)))
        yaws.append(rng.uniform(-np.pi, np.pi, 1))
        person += 1
    n = person - first_id
    position = np.concatenate(positions) if positions else np.zeros((0, 2))
    yaw = np.concatenate(yaws) if yaws else np.zeros(0)
    yaw = (yaw + np.pi) % (2 * np.pi) - np.pi
    return Frame(
        ids=np.arange(first_id, first_id + n),
        position=position,
        yaw=yaw,
        groups=tuple(groups),
        time=time,
        sequence=sequence,
    )


def toy_frames(seed: int, count: int, **kwargs) -> list[Frame]:
    """``count`` toy frames from one seed, times 0, 1, 2, ... seconds."""
    rng = np.random.default_rng(seed)
    return [toy_frame(rng, time=float(t), **kwargs) for t in range(count)]

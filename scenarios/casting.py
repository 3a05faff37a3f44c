"""Casting: heights and shoulder widths of the people a scenario puts on stage."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from scenarios.stage import PERSON_HEIGHT_M, PERSON_WIDTH_M, Role

__all__ = ["HEIGHT_MEAN_M", "HEIGHT_SD_M", "cast"]

HEIGHT_MEAN_M = 1.72  # metres, mean adult height
HEIGHT_SD_M = 0.08  # metres


def cast(
    rng: np.random.Generator,
    ids: Sequence[int],
    positions: np.ndarray,
    yaws: Sequence[float],
    *,
    parts: Sequence[str] | str = "person",
    present: Sequence[bool] | bool = True,
) -> tuple[Role, ...]:
    """People with drawn heights and widths (one draw per person, in id order).

    Args:
        rng: the generator.
        ids: person ids.
        positions: (n, 2) start positions, metres.
        yaws: (n,) start yaws, radians.
        parts: the part each plays (or one for all).
        present: whether each is in the room at the start (or one for all).
    """
    n = len(ids)
    heights = np.clip(rng.normal(HEIGHT_MEAN_M, HEIGHT_SD_M, size=n), *PERSON_HEIGHT_M)
    widths = rng.uniform(*PERSON_WIDTH_M, size=n)
    parts = [parts] * n if isinstance(parts, str) else list(parts)
    present = [present] * n if isinstance(present, bool) else list(present)
    positions = np.asarray(positions, dtype=np.float64)
    return tuple(
        Role(
            id=int(ids[k]),
            position=(float(positions[k, 0]), float(positions[k, 1])),
            yaw=float(yaws[k]),
            height=float(heights[k]),
            width=float(widths[k]),
            present=bool(present[k]),
            part=str(parts[k]),
        )
        for k in range(n)
    )

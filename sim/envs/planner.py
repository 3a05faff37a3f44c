"""Paths for the robot across a room of people: a cost-to-go field on a grid.

`plan_field` marks the cells the robot's centre must avoid (the walls, a disc around every
person, optionally an o-space) and spreads the walking distance to a goal over the free cells
(8-connected wavefront, vectorised with numpy). `next_point` follows the field downhill from the
robot for a short stretch: the point to steer to now. Cheap enough to redo a few times a second
in a room of a few tens of square metres at 0.1 m cells.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ["CELL_M", "Field", "next_point", "plan_field"]

CELL_M = 0.1  # metres, grid cell side
_DIAGONAL = math.sqrt(2.0)
_STEPS = ((1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0)) + tuple(
    (dx, dy, _DIAGONAL) for dx in (1, -1) for dy in (1, -1)
)


@dataclass(frozen=True, eq=False)
class Field:
    """Walking distance to a goal over a grid.

    Attributes:
        origin: (2,) room coordinates of cell (0, 0)'s centre, metres.
        cost: (nx, ny) distance to the goal in cells along free cells (inf: blocked or cut off).
        free: (nx, ny) bool, cells the robot's centre may be in.
        goal: (2,) the goal, metres.
    """

    origin: np.ndarray
    cost: np.ndarray
    free: np.ndarray
    goal: np.ndarray

    def cell(self, point: npt.ArrayLike) -> tuple[int, int]:
        """The cell holding ``point`` (clipped to the grid)."""
        p = (np.asarray(point, dtype=np.float64) - self.origin) / CELL_M
        nx, ny = self.cost.shape
        return (
            int(min(max(round(float(p[0])), 0), nx - 1)),
            int(min(max(round(float(p[1])), 0), ny - 1)),
        )

    def centre(self, i: int, j: int) -> np.ndarray:
        return self.origin + CELL_M * np.array([i, j], dtype=np.float64)


def plan_field(
    bounds: tuple[float, float, float, float],
    goal: npt.ArrayLike,
    obstacles: npt.ArrayLike,
    *,
    radius: float,
    keep_out: tuple[np.ndarray, float] | None = None,
) -> Field:
    """The walking distance to ``goal`` avoiding discs of ``radius`` around ``obstacles``.

    Args:
        bounds: (x_min, x_max, y_min, y_max) where the robot's centre may be, metres.
        goal: (2,) metres; its cell is free whatever covers it.
        obstacles: (k, 2) people's positions, metres.
        radius: metres around each obstacle the robot's centre must keep out of.
        keep_out: (centre (2,), radius) of one more disc to avoid (an o-space), or None.
    """
    x0, x1, y0, y1 = bounds
    nx = max(int(math.floor((x1 - x0) / CELL_M)) + 1, 1)
    ny = max(int(math.floor((y1 - y0) / CELL_M)) + 1, 1)
    origin = np.array([x0, y0], dtype=np.float64)
    xs = x0 + CELL_M * np.arange(nx)
    ys = y0 + CELL_M * np.arange(ny)
    free = np.ones((nx, ny), dtype=bool)
    discs = [(p, radius) for p in np.asarray(obstacles, dtype=np.float64).reshape(-1, 2)]
    if keep_out is not None:
        discs.append((np.asarray(keep_out[0], dtype=np.float64), float(keep_out[1])))
    for centre, r in discs:
        ix = np.flatnonzero(np.abs(xs - centre[0]) <= r)
        iy = np.flatnonzero(np.abs(ys - centre[1]) <= r)
        if ix.size and iy.size:
            dx = xs[ix, None] - centre[0]
            dy = ys[None, iy] - centre[1]
            block = dx * dx + dy * dy <= r * r
            free[ix[0] : ix[-1] + 1, iy[0] : iy[-1] + 1] &= ~block
    goal = np.asarray(goal, dtype=np.float64)
    field = Field(origin=origin, cost=np.full((nx, ny), np.inf), free=free, goal=goal)
    gi, gj = field.cell(goal)
    free[gi, gj] = True
    cost = field.cost
    cost[gi, gj] = 0.0
    padded = np.full((nx + 2, ny + 2), np.inf)
    for _ in range(4 * (nx + ny)):
        padded[1:-1, 1:-1] = cost
        best = cost.copy()
        for dx, dy, step in _STEPS:
            np.minimum(best, padded[1 + dx : nx + 1 + dx, 1 + dy : ny + 1 + dy] + step, out=best)
        best[~free] = np.inf
        if np.array_equal(best, cost):
            break
        cost[...] = best
    return field


def next_point(field: Field, start: npt.ArrayLike, *, reach: float = 0.5) -> np.ndarray | None:
    """Where to steer from ``start``: ``reach`` metres down the cost field (None: no way).

    From a blocked cell (the robot brushing someone), the lowest free cell next to it is taken
    first.
    """
    nx, ny = field.cost.shape
    i, j = field.cell(start)
    cost = field.cost
    if not math.isfinite(cost[i, j]):
        # Deep in a blocked patch: the nearest reachable cell within a metre.
        r = int(round(1.0 / CELL_M))
        a0, a1, b0, b1 = max(i - r, 0), min(i + r + 1, nx), max(j - r, 0), min(j + r + 1, ny)
        patch = cost[a0:a1, b0:b1]
        if not np.isfinite(patch).any():
            return None
        gx, gy = np.meshgrid(np.arange(a0, a1) - i, np.arange(b0, b1) - j, indexing="ij")
        near = np.where(np.isfinite(patch), gx * gx + gy * gy, np.inf)
        k = int(np.argmin(near))
        return field.centre(a0 + k // patch.shape[1], b0 + k % patch.shape[1])
    cells = max(int(round(reach / CELL_M)), 1)
    for _ in range(cells):
        if cost[i, j] == 0.0:
            break
        best, move = cost[i, j], None
        for dx, dy, _step in _STEPS:
            a, b = i + dx, j + dy
            if 0 <= a < nx and 0 <= b < ny and cost[a, b] < best:
                best, move = cost[a, b], (a, b)
        if move is None:
            break
        i, j = move
    if not math.isfinite(cost[i, j]):
        return None
    return field.centre(i, j)

"""Views of a whole dataset, static (they do not depend on the time cursor).

Entity tree under ``dataset``:

* ``dataset/characterisation/<name>/tightness`` and ``.../symmetry``: bar charts of the mean
  Tightness (metres) and Symmetry (degrees) of the ground-truth F-formations by group size
  (abscissa = size), and ``.../table``: the numbers, with group counts, as a Markdown table.
* ``dataset/pairs/<name>``: the (Distance, Effort Angle) scatter of pairs, x = distance in
  metres, y = effort angle in radians (the 2D view's y axis points down), coloured by label
  (``apart`` / ``together``) through an annotation context; ``.../regions``: the classifier's
  probability of "together" on a grid, as an image shaded from the ``apart`` to the
  ``together`` colour (the decision boundary is where the shades meet).
* ``dataset/stress/<name>/<curve>``: stress-test curves as bar charts over the stressed
  parameter (abscissa = its values, the curves' bars side by side around each value), and
  ``dataset/stress/<name>/table``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np
import numpy.typing as npt
import rerun as rr

from reform import Frame, GroupShapes, characterise, pair_labels
from reform.features import DISTANCE, EFFORT_ANGLE, frame_pair_features
from sim.recording import _colours

__all__ = [
    "DATASET_ROOT",
    "log_characterisation",
    "log_pair_scatter",
    "log_stress_curves",
    "pair_scatter_data",
]

DATASET_ROOT = "dataset"
REGION_GRID = 160  # pixels per side of the decision-region image
REGION_ALPHA = 110  # 0-255: how strongly the regions are shaded
MAX_EFFORT_RAD = 2.0 * math.pi  # radians: effort angles lie in [0, 2*pi]
POINT_RADIUS_UI = -2.0  # negative radii are in screen points: 2-point dots at any zoom
APART, TOGETHER = 0, 1  # pair labels and class ids


def _name(name: str) -> str:
    if not name or "/" in name:
        raise ValueError(f"name must be a non-empty entity name without '/', got {name!r}")
    return name


def log_characterisation(
    rec: rr.RecordingStream, source: GroupShapes | Iterable[Frame], *, name: str
) -> GroupShapes:
    """Mean Tightness and Symmetry by group size, as bar charts and a table (static).

    Args:
        rec: the recording stream.
        source: ``reform.characterise(frames)``, or the frames themselves.
        name: the dataset's name (one entity per dataset, e.g. ``"salsa"``).

    Returns:
        The characterisation logged.
    """
    shapes = source if isinstance(source, GroupShapes) else characterise(source)
    root = f"{DATASET_ROOT}/characterisation/{_name(name)}"
    means = shapes.mean_by_size()
    sizes = np.array(sorted(means), dtype=np.float64)
    tight = np.array([means[int(s)][0] for s in sizes])
    sym = np.array([means[int(s)][1] for s in sizes])
    rec.log(
        f"{root}/tightness",
        rr.BarChart(tight, abscissa=sizes, color=_colours.GROUP_PALETTE[0]),
        static=True,
    )
    rec.log(
        f"{root}/symmetry",
        rr.BarChart(sym, abscissa=sizes, color=_colours.GROUP_PALETTE[1]),
        static=True,
    )
    lines = [
        f"### {name}: F-formations by size",
        "",
        "| size | groups | mean Tightness (m) | mean Symmetry (deg) |",
        "|---:|---:|---:|---:|",
        *(f"| {s} | {c} | {t:.3f} | {y:.1f} |" for s, (t, y, c) in sorted(means.items())),
    ]
    rec.log(
        f"{root}/table",
        rr.TextDocument("\n".join(lines), media_type=rr.MediaType.MARKDOWN),
        static=True,
    )
    return shapes


def pair_scatter_data(frames: Iterable[Frame]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distance (m), Effort Angle (rad) and label of every pair of the annotated frames."""

    features, labels = [], []
    for frame in frames:
        if frame.groups is None or frame.n_people < 2:
            continue
        features.append(frame_pair_features(frame, features=(DISTANCE, EFFORT_ANGLE)))
        labels.append(pair_labels(frame))
    if not features:
        return np.zeros(0), np.zeros(0), np.zeros(0, dtype=np.int64)
    stacked = np.concatenate(features)
    return stacked[:, 0], stacked[:, 1], np.concatenate(labels).astype(np.int64)


def _probability_of_together(classifier: Any, grid: np.ndarray) -> np.ndarray:
    """P(together) on the grid from an estimator with ``predict_proba`` or a callable."""
    predict = getattr(classifier, "predict_proba", classifier)
    if not callable(predict):
        raise ValueError(
            "classifier must have predict_proba or be a callable (n, 2) -> probabilities, "
            f"got {type(classifier).__name__}"
        )
    proba = np.asarray(predict(grid), dtype=np.float64)
    if proba.ndim == 2 and proba.shape == (grid.shape[0], 2):
        classes = getattr(classifier, "classes_", None)
        column = 1 if classes is None else int(np.flatnonzero(np.asarray(classes) == TOGETHER)[0])
        proba = proba[:, column]
    if proba.shape != (grid.shape[0],):
        raise ValueError(
            f"classifier must give (n,) or (n, 2) probabilities for n = {grid.shape[0]} points, "
            f"got shape {proba.shape}"
        )
    return np.clip(proba, 0.0, 1.0)


def log_pair_scatter(
    rec: rr.RecordingStream,
    distance: npt.ArrayLike,
    effort_angle: npt.ArrayLike,
    label: npt.ArrayLike,
    *,
    name: str,
    classifier: Any | Callable[[np.ndarray], np.ndarray] | None = None,
    max_distance_m: float | None = None,
) -> None:
    """The (Distance, Effort Angle) scatter of pairs with the classifier's decision regions.

    Args:
        rec: the recording stream.
        distance: (n,) metres.
        effort_angle: (n,) radians in [0, 2*pi].
        label: (n,) 0 (apart) or 1 (together).
        name: entity name, e.g. ``"salsa"``.
        classifier: a fitted estimator with ``predict_proba`` on (m, 2) arrays of
            (distance, effort angle), or a callable returning P(together) for such an array;
            None for no regions.
        max_distance_m: right edge of the regions; default: the 99th percentile distance.

    Raises:
        ValueError: if the arrays differ in length, labels are not 0/1, or the classifier's
            output has the wrong shape.
    """
    d = np.asarray(distance, dtype=np.float64)
    ea = np.asarray(effort_angle, dtype=np.float64)
    y = np.asarray(label)
    if d.ndim != 1 or ea.shape != d.shape or y.shape != d.shape:
        raise ValueError(
            "distance, effort_angle and label must be 1-D of one length, got shapes "
            f"{d.shape}, {ea.shape} and {y.shape}"
        )
    if y.size and not np.all(np.isin(y, (APART, TOGETHER))):
        raise ValueError(f"label must hold 0 (apart) or 1 (together), got {np.unique(y).tolist()}")
    root = f"{DATASET_ROOT}/pairs/{_name(name)}"
    rec.log(
        root,
        rr.AnnotationContext(
            [
                rr.AnnotationInfo(id=APART, label="apart", color=_colours.APART),
                rr.AnnotationInfo(id=TOGETHER, label="together", color=_colours.TOGETHER),
            ]
        ),
        static=True,
    )
    rec.log(
        f"{root}/points",
        rr.Points2D(
            np.column_stack([d, ea]),
            class_ids=y.astype(np.uint16),
            radii=POINT_RADIUS_UI,
            show_labels=False,
            draw_order=10.0,
        ),
        static=True,
    )
    if classifier is None:
        return
    if max_distance_m is None:
        max_distance_m = float(np.percentile(d, 99)) if d.size else 3.0
    if not max_distance_m > 0:
        raise ValueError(f"max_distance_m must be > 0 metres, got {max_distance_m}")
    step_d = max_distance_m / REGION_GRID
    step_ea = MAX_EFFORT_RAD / REGION_GRID
    centres_d = (np.arange(REGION_GRID) + 0.5) * step_d
    centres_ea = (np.arange(REGION_GRID) + 0.5) * step_ea
    grid_d, grid_ea = np.meshgrid(centres_d, centres_ea)  # rows: effort angle, columns: distance
    p = _probability_of_together(classifier, np.column_stack([grid_d.ravel(), grid_ea.ravel()]))
    p = p.reshape(REGION_GRID, REGION_GRID, 1)
    rgb = (1.0 - p) * np.asarray(_colours.APART[:3]) + p * np.asarray(_colours.TOGETHER[:3])
    image = np.concatenate([rgb, np.full_like(p, REGION_ALPHA)], axis=2).round().astype(np.uint8)
    rec.log(f"{root}/regions", rr.Transform3D(scale=[step_d, step_ea, 1.0]), static=True)
    rec.log(f"{root}/regions", rr.Image(image, draw_order=-10.0), static=True)


def log_stress_curves(
    rec: rr.RecordingStream,
    x: npt.ArrayLike,
    curves: Mapping[str, npt.ArrayLike],
    *,
    x_label: str,
    name: str = "stress",
) -> None:
    """Stress-test curves (a score against a stressed parameter), as bar charts and a table.

    Args:
        rec: the recording stream.
        x: (k,) values of the stressed parameter (e.g. position noise in metres).
        curves: curve name (e.g. ``"reform F1"``) -> (k,) values at ``x``.
        x_label: what ``x`` is, with its unit, e.g. ``"position noise (m)"``.
        name: the stress test's name.
    """
    xs = np.asarray(x, dtype=np.float64)
    if xs.ndim != 1 or xs.size == 0:
        raise ValueError(f"x must be a non-empty 1-D array, got shape {xs.shape}")
    root = f"{DATASET_ROOT}/stress/{_name(name)}"
    header = ["| " + x_label + " | " + " | ".join(curves) + " |", "|---:|" + "---:|" * len(curves)]
    columns = []
    # Curves side by side: each level's group of bars spans 80% of the smallest gap.
    gap = float(np.min(np.diff(np.unique(xs)))) if np.unique(xs).size > 1 else 1.0
    width = 0.8 * gap / max(len(curves), 1)
    for index, (curve, values) in enumerate(curves.items()):
        ys = np.asarray(values, dtype=np.float64)
        if ys.shape != xs.shape:
            raise ValueError(f"curves[{curve!r}] must have shape {xs.shape} like x, got {ys.shape}")
        shift = (index - (len(curves) - 1) / 2.0) * width
        rec.log(
            f"{root}/{_name(curve.replace(' ', '_'))}",
            rr.BarChart(
                ys,
                abscissa=xs + shift,
                widths=np.full(xs.size, width),
                color=_colours.series_colour(index),
            ),
            static=True,
        )
        columns.append(ys)
    rows = [
        "| " + " | ".join([f"{xs[k]:g}", *(f"{c[k]:.3f}" for c in columns)]) + " |"
        for k in range(xs.size)
    ]
    rec.log(
        f"{root}/table",
        rr.TextDocument(
            "\n".join([f"### {name}", "", *header, *rows]), media_type=rr.MediaType.MARKDOWN
        ),
        static=True,
    )

"""The default layout a recording opens with: the 3D scene, the plots and the event log."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import rerun.blueprint as rrb

from sim.recording._dataset_views import DATASET_ROOT
from sim.recording._frames import WORLD_ROOT
from sim.recording._metrics import EVENTS_ENTITY, METRICS_ROOT
from sim.recording._scene import CAMERA_ROOT

__all__ = ["default_blueprint"]

SCENE_SHARE = 3.0  # the 3D scene takes 3/5 of the width
PLOTS_SHARE = 2.0
SCORE_RANGE = (0.0, 1.0)  # y range of the precision, recall and F1 plots
COUNT_MARGIN = 0.5  # F-formations: the counts plot spans -0.5 to its largest count + 0.5


def _eye(bounds: Sequence[float] | None) -> rrb.EyeControls3D | None:
    """An orbit camera over the room's near corner, looking at its middle."""
    if bounds is None:
        return None
    x0, x1, y0, y1 = (float(b) for b in bounds)
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
    size = max(x1 - x0, y1 - y0)
    position = centre + np.array([-0.45, -0.75, 0.75]) * size
    return rrb.EyeControls3D(
        kind=rrb.Eye3DKind.Orbital, position=position, look_target=centre, eye_up=[0.0, 0.0, 1.0]
    )


def default_blueprint(
    *,
    scene: bool = True,
    scores: bool = True,
    max_groups: int | None = None,
    events: bool = True,
    bounds: Sequence[float] | None = None,
    cameras: Sequence[str] = (),
    characterisation: Sequence[str] = (),
    pairs: Sequence[str] = (),
    stress: Sequence[str] = (),
) -> rrb.Blueprint:
    """The layout: scene on the left; running scores, group counts and events on the right.

    Only panels for what the recording holds: a run without detectors gets no score plots, one
    without group counts no counts plot, one without events no event log, one without a scene
    (a stress test's curves) no run tab. Every plot has its y range set to hold all its data
    (a plot left to find its own range opens on an empty -1 to 1 axis when its values are
    constant or not drawn yet), and panel names carry the units.

    Dataset views, when any are named, get a second tab.

    Args:
        scene: include the run tab: the 3D scene of ``world/`` and the plots beside it.
        scores: include the running precision / recall / F1 plots (runs with ground truth and
            detectors).
        max_groups: the most F-formations any tree holds in one frame, for the range of the
            "F-formations per frame" plot; None: no group counts are logged, no plot.
        events: include the event log (``events`` holds some).
        bounds: ``(x_min, x_max, y_min, y_max)`` metres of the room, to aim the 3D camera from
            a raised corner; None lets the viewer choose.
        cameras: camera names logged by ``log_camera_images`` (shown under the scene).
        characterisation: dataset names logged by ``log_characterisation``.
        pairs: names logged by ``log_pair_scatter``.
        stress: names logged by ``log_stress_curves``.
    """
    if max_groups is not None and (isinstance(max_groups, bool) or int(max_groups) < 0):
        raise ValueError(f"max_groups must be None or an int >= 0, got {max_groups!r}")
    side: list[rrb.View] = []
    if scores:
        side.append(
            rrb.TimeSeriesView(
                origin=f"/{METRICS_ROOT}/f1",
                name="Running F1 (T = 2/3), per frame",
                axis_y=rrb.ScalarAxis(range=SCORE_RANGE),
            )
        )
        side.append(
            rrb.TimeSeriesView(
                origin=f"/{METRICS_ROOT}",
                contents=["$origin/precision/**", "$origin/recall/**"],
                name="Running precision and recall (T = 2/3), per frame",
                axis_y=rrb.ScalarAxis(range=SCORE_RANGE),
            )
        )
    if max_groups is not None:
        side.append(
            rrb.TimeSeriesView(
                origin=f"/{METRICS_ROOT}/groups",
                name="F-formations per frame (count)",
                axis_y=rrb.ScalarAxis(
                    range=(-COUNT_MARGIN, max(int(max_groups), 1) + COUNT_MARGIN)
                ),
            )
        )
    if events:
        side.append(rrb.TextLogView(origin=f"/{EVENTS_ENTITY}", name="Events"))
    world: rrb.Container | rrb.View = rrb.Spatial3DView(
        origin=f"/{WORLD_ROOT}", name="Scene (m)", eye_controls=_eye(bounds)
    )
    if cameras:
        world = rrb.Vertical(
            world,
            rrb.Horizontal(
                *(
                    rrb.Spatial2DView(origin=f"/{CAMERA_ROOT}/{c}", name=f"{c} camera")
                    for c in cameras
                )
            ),
            row_shares=[3.0, 1.0],
        )
    if side:
        run: rrb.Container | rrb.View = rrb.Horizontal(
            world, rrb.Vertical(*side), column_shares=[SCENE_SHARE, PLOTS_SHARE], name="Run"
        )
    else:
        run = rrb.Horizontal(world, name="Run")
    dataset: list[rrb.View] = []
    for name in characterisation:
        root = f"/{DATASET_ROOT}/characterisation/{name}"
        dataset.append(
            rrb.BarChartView(
                origin=f"{root}/tightness", name=f"{name}: Tightness (m) by group size (people)"
            )
        )
        dataset.append(
            rrb.BarChartView(
                origin=f"{root}/symmetry", name=f"{name}: Symmetry (deg) by group size (people)"
            )
        )
        dataset.append(
            rrb.TextDocumentView(origin=f"{root}/table", name=f"{name}: characterisation")
        )
    for name in pairs:
        dataset.append(
            rrb.Spatial2DView(
                origin=f"/{DATASET_ROOT}/pairs/{name}",
                name=f"{name}: pairs, distance (m, right) x effort angle (rad, down)",
            )
        )
    for name in stress:
        root = f"/{DATASET_ROOT}/stress/{name}"
        dataset.append(
            rrb.BarChartView(origin=root, contents=["$origin/**", f"- {root}/table"], name=name)
        )
        dataset.append(rrb.TextDocumentView(origin=f"{root}/table", name=f"{name}: table"))
    if not scene and not dataset:
        raise ValueError("a layout needs the scene or a dataset view, got neither")
    if not dataset:
        return rrb.Blueprint(run, collapse_panels=False)
    grid = rrb.Grid(*dataset, name="Dataset")
    if not scene:
        return rrb.Blueprint(grid, collapse_panels=False)
    return rrb.Blueprint(rrb.Tabs(run, grid, active_tab=0), collapse_panels=False)

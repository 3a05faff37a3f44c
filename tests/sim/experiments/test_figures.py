"""Figures: a matched group wears one colour in every panel; axes carry units."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from reform import Frame
from sim.experiments.figures import pyplot, top_view, top_view_figure
from sim.recording import group_colour


def _pixels_of(image: np.ndarray, colour) -> np.ndarray:
    """(k, 2) row, column of the pixels exactly of ``colour`` (sRGB 0-255)."""
    rgb = np.rint(image[..., :3] * 255).astype(int)
    return np.argwhere(np.all(rgb == np.array(colour[:3]), axis=-1))


def test_top_view_colours_a_matched_group_as_the_truth_does(tmp_path: Path) -> None:
    # Two pairs far apart: truth {1,2} (track 1) and {3,4} (track 2). The detector finds only
    # {3,4}: coloured on its own it would take the first colour; matched, it takes track 2's.
    frame = Frame(
        ids=np.array([1, 2, 3, 4]),
        position=np.array([[-3.0, 0.0], [-2.2, 0.0], [2.2, 0.0], [3.0, 0.0]]),
        yaw=np.array([0.0, np.pi, 0.0, np.pi]),
        groups=((1, 2), (3, 4)),
    )
    path = top_view(
        frame,
        {"ground truth": frame.partition(), "detector": ((1,), (2,), (3, 4))},
        tmp_path / "view.png",
    )
    image = pyplot().imread(path)
    width = image.shape[1]
    first, second = group_colour(1), group_colour(2)
    truth_half = image[:, : width // 2]
    detector_half = image[:, width // 2 :]
    assert len(_pixels_of(truth_half, first)) > 20 and len(_pixels_of(truth_half, second)) > 20
    assert len(_pixels_of(detector_half, second)) > 20
    assert len(_pixels_of(detector_half, first)) == 0
    # The matched pair sits on the right of its panel, where the truth's {3,4} is on its own.
    columns = _pixels_of(detector_half, second)[:, 1]
    assert columns.min() > detector_half.shape[1] // 2


def test_top_view_axes_carry_metres() -> None:
    frame = Frame(
        ids=np.array([1, 2]), position=np.array([[0.0, 0.0], [1.0, 0.0]]), yaw=np.zeros(2)
    )
    figure = top_view_figure(frame, {"a": ((1, 2),), "b": ((1,), (2,))})
    labels = [(ax.get_xlabel(), ax.get_ylabel()) for ax in figure.axes]
    assert labels == [("x (m)", "y (m)"), ("x (m)", "")]
    pyplot().close(figure)

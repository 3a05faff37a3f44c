"""Figures for reports, as PNG files (matplotlib, no display needed).

* :func:`score_bars`: grouped bars (one group per test set, one bar per detector) with error
  bars, e.g. F1 at T = 2/3 with bootstrap intervals;
* :func:`top_view`: one frame from above: people as discs with facing arrows, groups as
  rings, truth and detectors side by side, a matched group in one colour in every panel.

matplotlib is imported inside the functions, with the non-interactive ``Agg`` backend; every
file is written atomically.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from reform.atomic import atomic_path
from reform.frame import Frame, Group
from sim.recording import fformations, group_colour, match_tracks

__all__ = ["Bar", "pyplot", "save_png", "score_bars", "top_view", "top_view_figure"]

DPI = 110  # dots per inch of the PNG files
WIDTH_IN = 8.0  # inches, figure width


@dataclass(frozen=True)
class Bar:
    """One bar: a label, a value and, optionally, an interval around it.

    Attributes:
        label: the series it belongs to (one colour per label across groups).
        value: the bar's height.
        low: lower end of its interval, or None.
        high: upper end of its interval, or None.
    """

    label: str
    value: float
    low: float | None = None
    high: float | None = None


def pyplot() -> Any:
    """matplotlib.pyplot on the file-only Agg backend (no screen needed)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def save_png(fig: Any, path: str | os.PathLike[str], *, dpi: int = DPI) -> Path:
    """Writes ``fig`` to ``path`` as a PNG, atomically, and closes it."""
    plt = pyplot()
    target = Path(path)
    with atomic_path(target) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return target


def score_bars(
    groups: Mapping[str, Sequence[Bar]],
    path: str | os.PathLike[str],
    *,
    ylabel: str,
    title: str = "",
    reference: Mapping[str, float] | None = None,
) -> Path:
    """Grouped bars: one group per key of ``groups``, one colour per bar label.

    Args:
        groups: group name (e.g. a test set) -> its bars.
        path: the PNG file to write.
        ylabel: the value's name and unit.
        title: figure title.
        reference: horizontal reference lines, label -> value (e.g. the paper's F1).

    Returns:
        The path written.
    """
    if not groups or not any(groups.values()):
        raise ValueError("groups must hold at least one bar, got none")
    plt = pyplot()
    labels = list(dict.fromkeys(bar.label for bars in groups.values() for bar in bars))
    width = 0.8 / len(labels)
    fig, ax = plt.subplots(figsize=(WIDTH_IN, 3.8))
    colours = plt.get_cmap("tab10")
    for g, bars in enumerate(groups.values()):
        for bar in bars:
            k = labels.index(bar.label)
            x = g + (k - (len(labels) - 1) / 2) * width
            error = None
            if bar.low is not None and bar.high is not None:
                error = [[max(bar.value - bar.low, 0.0)], [max(bar.high - bar.value, 0.0)]]
            ax.bar(
                x,
                bar.value,
                width=width * 0.95,
                color=colours(k % 10),
                yerr=error,
                capsize=2,
                label=bar.label,
            )
    ax.set_xticks(range(len(groups)), list(groups))
    for name, value in (reference or {}).items():
        ax.axhline(value, color="0.3", linestyle="--", linewidth=0.8)
        right = ax.get_xlim()[1]
        ax.annotate(name, (right, value), ha="right", va="bottom", fontsize=7, color="0.3")
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles, strict=True))
    ax.legend(
        unique.values(), unique.keys(), fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0)
    )
    ax.grid(axis="y", alpha=0.3)
    return save_png(fig, path)


def top_view(
    frame: Frame,
    partitions: Mapping[str, Sequence[Group]],
    path: str | os.PathLike[str],
    *,
    title: str = "",
) -> Path:
    """One frame from above, once per partition (e.g. ground truth, REFORM, GCFF).

    People are discs with an arrow along their body yaw (robots are squares); members of a
    group of two or more share a colour and a ring through them; singletons are grey. The first
    partition is the reference (the ground truth): each other panel's group matched to one of
    its groups (`reform.match_groups`, largest summed Jaccard index) wears that group's colour,
    and an unmatched group a colour no reference group has (`sim.recording` uses the same
    colours). Axes are the room's x and y in metres.

    Args:
        frame: the frame.
        partitions: panel title -> a full partition of the frame's ids; the first is the
            reference.
        path: the PNG file to write.
        title: figure title.

    Returns:
        The path written.
    """
    return save_png(top_view_figure(frame, partitions, title=title), path)


def top_view_figure(
    frame: Frame, partitions: Mapping[str, Sequence[Group]], *, title: str = ""
) -> Any:
    """The matplotlib figure :func:`top_view` saves (for a caller to adjust or show)."""
    if not partitions:
        raise ValueError("partitions must hold at least one partition, got none")
    plt = pyplot()
    panels = len(partitions)
    fig, axes = plt.subplots(1, panels, figsize=(3.3 * panels, 3.6), squeeze=False)
    names = list(partitions)
    reference_tracks, tracks = match_tracks(
        partitions[names[0]], {name: partitions[name] for name in names[1:]}
    )
    tracks[names[0]] = reference_tracks
    row_of = {int(i): k for k, i in enumerate(frame.ids)}
    lo = frame.position.min(axis=0) - 0.8
    hi = frame.position.max(axis=0) + 0.8
    for index, (ax, name) in enumerate(zip(axes[0], names, strict=True)):
        colour_of: dict[int, Any] = {}
        for group, track in zip(fformations(partitions[name]), tracks[name], strict=True):
            colour = _rgb(group_colour(track))
            rows = [row_of[m] for m in group if m in row_of]
            centre = frame.position[rows].mean(axis=0)
            radius = float(np.mean(np.linalg.norm(frame.position[rows] - centre, axis=1)))
            ax.add_patch(
                plt.Circle(centre, radius, fill=False, color=colour, linewidth=1.2, alpha=0.8)
            )
            for m in group:
                colour_of[m] = colour
        for k, person in enumerate(frame.ids.tolist()):
            x, y = frame.position[k]
            colour = colour_of.get(int(person), "0.6")
            marker = "s" if frame.is_robot[k] else "o"
            ax.plot(x, y, marker=marker, color=colour, markersize=7, markeredgecolor="k")
            dx, dy = 0.35 * np.cos(frame.yaw[k]), 0.35 * np.sin(frame.yaw[k])
            ax.arrow(x, y, dx, dy, head_width=0.08, color=colour, length_includes_head=True)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("x (m)", fontsize=8)
        if index == 0:
            ax.set_ylabel("y (m)", fontsize=8)
        ax.tick_params(labelsize=7)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def _rgb(colour: Sequence[int]) -> tuple[float, float, float]:
    """An sRGB 0-255 colour as matplotlib's 0-1 triple."""
    return (colour[0] / 255.0, colour[1] / 255.0, colour[2] / 255.0)

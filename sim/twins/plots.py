"""A page of plots, a venue twin against its recording: spacing, people, orientations, motion."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from reform.frame import Frame
from sim.experiments.figures import pyplot, save_png
from sim.twins.description import Twin
from sim.twins.statistics import nearest_neighbour_distances

__all__ = ["plot_twin"]

REAL_COLOUR = "#333333"
TWIN_COLOUR = "#d95f02"


def _people(frames: Sequence[Frame]) -> np.ndarray:
    return np.array([int(np.sum(~f.is_robot)) for f in frames])


def plot_twin(
    twin: Twin, real: Sequence[Frame], sample: Sequence[Frame], path: str | os.PathLike[str]
) -> Path:
    """Writes the page (PNG): nearest-neighbour distances, people per frame, yaws and the fitted
    statistics, real beside twin. ``real`` are the recording's frames, ``sample`` the twin's."""
    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    nn_real, nn_twin = nearest_neighbour_distances(real), nearest_neighbour_distances(sample)
    top = float(np.quantile(np.concatenate([nn_real, nn_twin]), 0.99))
    bins = np.linspace(0.0, top, 40)
    ax = axes[0, 0]
    ax.hist(nn_real, bins=bins, density=True, histtype="step", color=REAL_COLOUR, label="real")
    ax.hist(nn_twin, bins=bins, density=True, histtype="step", color=TWIN_COLOUR, label="twin")
    ax.set_xlabel("nearest-neighbour distance (dataset units, m)")
    ax.set_title("spacing")
    ax.legend()
    ax = axes[0, 1]
    people = np.concatenate([_people(real), _people(sample)])
    bins = np.arange(people.min() - 0.5, people.max() + 1.5)
    ax.hist(_people(real), bins=bins, density=True, histtype="step", color=REAL_COLOUR)
    ax.hist(_people(sample), bins=bins, density=True, histtype="step", color=TWIN_COLOUR)
    ax.set_xlabel("people per frame")
    ax.set_title("people")
    ax = axes[1, 0]
    bins = np.linspace(-np.pi, np.pi, 73)
    ax.hist(np.concatenate([f.yaw for f in real]), bins=bins, density=True, histtype="step",
            color=REAL_COLOUR)  # fmt: skip
    ax.hist(np.concatenate([f.yaw for f in sample]), bins=bins, density=True, histtype="step",
            color=TWIN_COLOUR)  # fmt: skip
    ax.set_xlabel("recorded yaw (rad)")
    ax.set_title("orientation coding")
    ax = axes[1, 1]
    rows = [f for f in twin.fitted if isinstance(f.real, (int, float)) and f.real]
    rows = [f for f in rows if isinstance(f.twin, (int, float))]
    ratio = [float(f.twin) / float(f.real) for f in rows]
    ax.barh(range(len(rows)), ratio, color=TWIN_COLOUR)
    ax.axvline(1.0, color=REAL_COLOUR)
    ax.set_yticks(range(len(rows)), [f.statistic[:38] for f in rows], fontsize=7)
    ax.set_xlabel("twin / real")
    ax.set_title("fitted statistics")
    fig.suptitle(f"venue twin of {twin.name} ({twin.mode}): real (grey) against twin (orange)")
    fig.tight_layout()
    return save_png(fig, path)

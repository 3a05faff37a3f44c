"""The field's detectors on the real datasets: scored against the majority baseline.

Shared by ``tests/reform/test_{proximity,dominant_sets,gtcg,hough}.py``. The datasets come from
the one shared folder (``shared_datasets`` in ``tests/conftest.py``); a dataset missing from it
skips its test, and a missing folder skips them all.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from reform import Frame, evaluate, make_detector, run_detector
from reform.datasets import load_dataset

__all__ = [
    "MARGIN",
    "REAL_DATASETS",
    "annotated_frames",
    "assert_beats_majority",
    "assert_same_groups_moved_and_relabelled",
    "moved_and_relabelled",
    "scores",
]

REAL_DATASETS = ("salsa", "babble", "coffeebreak", "synth")
SALSA_EVERY = 8  # SALSA frames scored: every 8th (143 of 1,143), to keep the tests short
MARGIN = 0.2  # how far (F1 at T = 2/3, as a fraction) a detector must clear the majority baseline


@functools.cache
def _annotated(folder: str, name: str) -> tuple[Frame, ...]:
    frames = [f for f in load_dataset(folder).frames if f.groups is not None]
    return tuple(frames[::SALSA_EVERY] if name == "salsa" else frames)


def annotated_frames(shared_datasets: Path, name: str) -> tuple[Frame, ...]:
    """The annotated frames of dataset ``name`` of the shared folder (SALSA thinned); skips
    when the folder holds no such dataset."""
    folder = shared_datasets / name
    if not folder.is_dir():
        pytest.skip(f"dataset {name} not found at {folder}")
    return _annotated(str(folder), name)


def scores(detector: str, frames: tuple[Frame, ...], **options: Any) -> tuple[float, float]:
    """F1 at T = 2/3 and at T = 1 (F1 of the frame means) of a catalogued detector."""
    predicted = run_detector(detector, make_detector(detector, **options), frames)
    evaluation = evaluate(frames, predicted)
    return evaluation.at("2/3").f1, evaluation.at("1").f1


def assert_beats_majority(detector: str, frames: tuple[Frame, ...], **options: Any) -> None:
    """The detector's F1 at T = 2/3 clears the majority baseline's by :data:`MARGIN`."""
    f1, _ = scores(detector, frames, **options)
    floor, _ = scores("majority", frames)
    assert np.isfinite(f1)
    assert f1 >= floor + MARGIN, f"{detector}: F1 {f1:.3f} against majority {floor:.3f}"


def moved_and_relabelled(frame: Frame, rng: np.random.Generator) -> tuple[Frame, dict[int, int]]:
    """``frame`` turned and moved on the floor, its people listed in another order under other
    ids; and the map from the new ids back to the old."""
    turn = rng.uniform(-np.pi, np.pi)
    shift = rng.uniform(-50.0, 50.0, 2)
    rotation = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    order = rng.permutation(frame.n_people)
    new_ids = rng.choice(10**6, size=frame.n_people, replace=False) + 1000
    yaw = (frame.yaw + turn + np.pi) % (2 * np.pi) - np.pi
    moved = Frame(
        ids=new_ids[order],
        position=(frame.position @ rotation.T + shift)[order],
        yaw=yaw[order],
    )
    return moved, dict(zip(new_ids.tolist(), frame.ids.tolist(), strict=True))


def assert_same_groups_moved_and_relabelled(detector: Any, seed: int, scenes: int = 5) -> None:
    """Dense random scenes (30 people on 6 m x 6 m, any heading) give the same groups turned,
    moved, reordered and renamed: no tie in them is broken by where or in which order people
    are listed."""
    rng = np.random.default_rng(seed)
    for _ in range(scenes):
        frame = Frame(
            ids=np.arange(1, 31),
            position=rng.uniform(0.0, 6.0, (30, 2)),
            yaw=rng.uniform(-np.pi, np.pi, 30),
        )
        moved, back = moved_and_relabelled(frame, rng)
        (before,) = detector.predict([frame])
        (after,) = detector.predict([moved])
        assert {frozenset(g) for g in before} == {frozenset(back[int(m)] for m in g) for g in after}

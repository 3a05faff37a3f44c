"""Train/test splits by time: neighbouring frames are near-duplicates, so never split at random.

* :func:`time_split`: per sequence, the first share of annotated frames (by time) for training,
  the rest for testing.
* :func:`time_blocks`: per sequence, consecutive blocks of frames, for cross-validation whose
  folds are stretches of time (use the block as the ``groups`` of a scikit-learn ``GroupKFold``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from reform.frame import Frame, check_frames

DEFAULT_TRAIN_FRACTION = 0.6  # share of each sequence's annotated frames used for training

__all__ = ["DEFAULT_TRAIN_FRACTION", "time_blocks", "time_split"]


def time_split(
    frames: Iterable[Frame], train_fraction: float = DEFAULT_TRAIN_FRACTION
) -> tuple[tuple[Frame, ...], tuple[Frame, ...]]:
    """Splits frames by time within each sequence.

    In each sequence the annotated frames are ordered by time; the first
    ``round(train_fraction * count)`` of them (rounding halves up) go to training and the rest to
    testing. A frame without ground truth goes to the side of the cut its time falls on (at the
    cut's time or later: testing). Frames keep their input order within each side.

    Args:
        frames: frames of one or more sequences (a Dataset works too).
        train_fraction: share of each sequence's annotated frames for training, in (0, 1).

    Returns:
        ``(train, test)`` tuples of frames.

    Raises:
        ValueError: if ``train_fraction`` is not in (0, 1).
    """
    if isinstance(train_fraction, bool) or not 0.0 < float(train_fraction) < 1.0:
        raise ValueError(f"train_fraction must lie in (0, 1), got {train_fraction!r}")
    frames = check_frames(frames, caller="time_split")
    cut_time: dict[str, float] = {}
    for sequence in dict.fromkeys(frame.sequence for frame in frames):
        times = sorted(f.time for f in frames if f.sequence == sequence and f.groups is not None)
        if not times:
            times = sorted(f.time for f in frames if f.sequence == sequence)
        n_train = math.floor(train_fraction * len(times) + 0.5)
        cut_time[sequence] = times[n_train] if n_train < len(times) else math.inf
    train = tuple(f for f in frames if f.time < cut_time[f.sequence])
    test = tuple(f for f in frames if f.time >= cut_time[f.sequence])
    return train, test


def time_blocks(frames: Iterable[Frame], n_blocks: int = 5) -> np.ndarray:
    """Block index of every frame: each sequence cut into ``n_blocks`` stretches of time.

    Within a sequence the frames are ordered by time and cut into ``n_blocks`` runs of (nearly)
    equal counts; block ``b`` of every sequence gets the same index ``b``, so a fold of
    ``GroupKFold`` over these blocks holds one stretch of time of each sequence.

    Args:
        frames: frames of one or more sequences.
        n_blocks: blocks per sequence, >= 2.

    Returns:
        (len(frames),) int64 block indices in ``[0, n_blocks)``, in the frames' order.
    """
    if isinstance(n_blocks, bool) or int(n_blocks) != n_blocks or n_blocks < 2:
        raise ValueError(f"n_blocks must be an integer >= 2, got {n_blocks!r}")
    frames = check_frames(frames, caller="time_blocks")
    blocks = np.zeros(len(frames), dtype=np.int64)
    sequences = np.array([frame.sequence for frame in frames], dtype=object)
    times = np.array([frame.time for frame in frames], dtype=np.float64)
    for sequence in dict.fromkeys(sequences.tolist()):
        rows = np.flatnonzero(sequences == sequence)
        ordered = rows[np.argsort(times[rows], kind="stable")]
        blocks[ordered] = np.arange(ordered.size) * int(n_blocks) // max(1, ordered.size)
    return blocks

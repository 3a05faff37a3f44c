"""The majority baseline: every pair "not together", i.e. everyone alone.

In F-formation data most pairs of people are not in the same group, so always answering
"not together" already scores a high pairwise accuracy (85.3 % on SALSA's test split in the
REFORM paper) while finding no group at all. It is the floor any detector must clear.
"""

from __future__ import annotations

from collections.abc import Sequence

from reform.estimator import Estimator
from reform.frame import Frame, Group, check_frames

__all__ = ["Majority"]


class Majority(Estimator):
    """Majority-class detector: predicts every person a singleton.

    It follows the detector protocol (``fit(frames) -> self``, ``predict(frames)`` -> one full
    partition per frame) and learns nothing, so ``fit`` is optional and ``predict`` works on a
    fresh instance.

    Example:
        >>> Majority().predict(frames)[0]   # doctest: +SKIP
        ((1,), (2,), (3,))
    """

    def fit(self, frames: Sequence[Frame]) -> Majority:
        """Checks ``frames`` and returns ``self`` (there is nothing to learn)."""
        check_frames(frames)
        return self

    def predict(self, frames: Sequence[Frame]) -> list[tuple[Group, ...]]:
        """One partition per frame: each person alone, in the frame's row order."""
        return [tuple((int(i),) for i in frame.ids) for frame in check_frames(frames)]

    def __sklearn_is_fitted__(self) -> bool:
        return True

"""Tracking errors applied to frames: position noise, orientation noise, dropped people.

One model of a tracker's errors, :class:`TrackerNoise`, serves everything that makes them: the
stress tests' :class:`Perturbation` (on any :class:`reform.Frame`, real or simulated, so the same
stress test runs on SALSA as on a synthetic party), the robot's sensor (`sim.Sensor`, after its
field of view and occlusion have decided who is visible) and the environments' view
(`sim.envs.view.Eyes`). Gaussian noise goes on every tracked person's ground-plane position
(metres per axis) and body yaw (radians), and each is missed with a probability (a *dropout*:
they vanish from the frame).

Conventions:
    * Robots are left as they are (a robot knows its own pose) unless asked
      (``Perturbation.perturb_robots``).
    * Head poses, where present, get the same kind of noise as the body, drawn separately, and
      disappear with their person. A missing head (NaN) stays missing.
    * Every yaw of the result is wrapped again to ``[-pi, pi)``.
    * The ground truth of a perturbed frame is the original one restricted to the people still
      in it (:func:`restrict_groups`: a group of which one member remains becomes that member
      alone), as a tracker's output would be annotated; the detector is not blamed for people it
      was never given. When the frame carries ``listed_groups`` (an annotation naming people the
      tracker lost), they are kept as they are: the people dropped join those already missing.
    * **One order of random numbers, common to every level.** For a frame of ``n`` people the
      draws are made for every one of them, tracked or not, affected or not, whatever the
      levels, in this order: standard normals for position (n, 2), head position (n, 2), yaw
      (n,), head yaw (n,), then uniforms (n,) for dropouts (``6 n`` numbers). The noise at
      level ``s`` is ``s`` times the same standard normal, and the people dropped at rate ``p``
      are those whose uniform is below ``p``, so a generator seeded alike gives nested dropouts
      and noise that only grows along a sweep (curves over the levels differ by the level, not
      by the luck of the draw), and what the sensor sees does not change the draws.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from reform._checks import check_levels
from reform.frame import Frame, Group, wrap_angle

__all__ = ["NoisyPoses", "Perturbation", "TrackerNoise", "restrict_groups"]


def restrict_groups(
    groups: tuple[Group, ...] | None, kept_ids: Iterable[int]
) -> tuple[Group, ...] | None:
    """``groups`` with only the members in ``kept_ids``; groups left empty are dropped.

    ``None`` (a frame that is not annotated) stays ``None``.
    """
    if groups is None:
        return None
    kept = kept_ids if isinstance(kept_ids, (set, frozenset)) else {int(i) for i in kept_ids}
    out = []
    for group in groups:
        members = tuple(m for m in group if m in kept)
        if members:
            out.append(members)
    return tuple(out)


def _mask(name: str, value: np.ndarray | None, n: int, default: np.ndarray) -> np.ndarray:
    if value is None:
        return default
    mask = np.asarray(value)
    if mask.dtype != np.bool_ or mask.shape != (n,):
        raise ValueError(
            f"{name} must be a bool array of shape ({n},), got {mask.dtype} {mask.shape}"
        )
    return mask


@dataclass(frozen=True, eq=False)
class NoisyPoses:
    """Poses as the tracker reports them, row for row with the poses given.

    Attributes:
        kept: (n,) bool, rows not dropped (every row not affected is kept).
        position: (n, 2) positions with noise where affected, metres.
        yaw: (n,) yaws with noise where affected, every one wrapped, radians.
        head_position: (n, 2) head positions likewise, or None when none were given.
        head_yaw: (n,) head yaws likewise (NaN stays NaN), or None.
    """

    kept: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    head_position: np.ndarray | None
    head_yaw: np.ndarray | None


@dataclass(frozen=True)
class TrackerNoise:
    """A tracker's errors on the people it has: Gaussian noise on poses, and dropouts.

    Attributes:
        position_std: standard deviation of the noise on each position coordinate (body and
            head), metres.
        yaw_std: standard deviation of the noise on each yaw (body and head), radians.
        dropout: probability that a tracked person is missing from a frame, in [0, 1].
    """

    position_std: float = 0.0
    yaw_std: float = 0.0
    dropout: float = 0.0

    def __post_init__(self) -> None:
        levels = ("position_std", "yaw_std")
        check_levels(self, f"{type(self).__name__}.", levels, probabilities=("dropout",))

    @property
    def is_identity(self) -> bool:
        """True when it changes nothing."""
        return self.position_std == 0.0 and self.yaw_std == 0.0 and self.dropout == 0.0

    def perturb_poses(
        self,
        rng: np.random.Generator,
        position: np.ndarray,
        yaw: np.ndarray,
        head_position: np.ndarray | None = None,
        head_yaw: np.ndarray | None = None,
        *,
        affected: np.ndarray,
    ) -> NoisyPoses:
        """Noise and dropouts on arrays of poses: the model itself, without a Frame.

        Draws ``6 n`` numbers from ``rng`` in the module's order, whatever the levels and
        ``affected``. The arrays given are not modified.

        Args:
            rng: the generator.
            position: (n, 2) positions, metres.
            yaw: (n,) yaws, radians.
            head_position: optional (n, 2) head positions, metres (NaN rows: no head).
            head_yaw: optional (n,) head yaws, radians; given with ``head_position``.
            affected: (n,) bool, who gets noise and may drop out.

        Returns:
            The noisy poses and who was kept.
        """
        n = len(yaw)
        if np.shape(position) != (n, 2) or np.shape(affected) != (n,):
            raise ValueError(
                f"position must have shape ({n}, 2) and affected ({n},) for {n} yaws, got "
                f"{np.shape(position)} and {np.shape(affected)}"
            )
        position_z = rng.standard_normal((n, 2))
        head_position_z = rng.standard_normal((n, 2))
        yaw_z = rng.standard_normal(n)
        head_yaw_z = rng.standard_normal(n)
        uniform = rng.random(n)
        noisy = affected[:, None]
        kept = ~(affected & (uniform < self.dropout))
        out_position = position + np.where(noisy, position_z * self.position_std, 0.0)
        out_yaw = wrap_angle(yaw + np.where(affected, yaw_z * self.yaw_std, 0.0))
        out_head_position = out_head_yaw = None
        if head_position is not None:
            out_head_position = head_position + np.where(
                noisy, head_position_z * self.position_std, 0.0
            )
            out_head_yaw = wrap_angle(head_yaw + np.where(affected, head_yaw_z * self.yaw_std, 0.0))
        return NoisyPoses(
            kept=kept,
            position=out_position,
            yaw=out_yaw,
            head_position=out_head_position,
            head_yaw=out_head_yaw,
        )

    def apply(
        self,
        frame: Frame,
        rng: np.random.Generator,
        *,
        tracked: np.ndarray | None = None,
        affected: np.ndarray | None = None,
        hidden_heads: np.ndarray | None = None,
    ) -> Frame:
        """The frame as the tracker reports it.

        Args:
            frame: the true frame (not modified).
            rng: the generator; every call draws ``6 n`` numbers for a frame of ``n`` people
                (see the module docstring), whatever the levels and masks.
            tracked: (n,) bool, who the tracker has before dropouts (a sensor's field of view
                and occlusion decide it); the others are left out of the result. Default:
                everyone.
            affected: (n,) bool, who gets noise and may drop out. Default: the tracked people
                who are not robots.
            hidden_heads: (n,) bool, whose head pose is not reported (NaN in the result).
                Default: none.

        Returns:
            A new frame of the people kept, with noisy poses, the ground truth restricted to
            them, and ``listed_groups``, time and sequence as the frame has them.
        """
        if not isinstance(frame, Frame):
            raise ValueError(f"frame must be a reform.Frame, got {type(frame).__name__}")
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        n = frame.n_people
        tracked = _mask("tracked", tracked, n, np.ones(n, dtype=bool))
        affected = _mask("affected", affected, n, tracked & ~frame.is_robot)
        noisy = self.perturb_poses(
            rng,
            frame.position,
            frame.yaw,
            frame.head_position,
            frame.head_yaw,
            affected=affected,
        )
        hidden = _mask("hidden_heads", hidden_heads, n, np.zeros(n, dtype=bool))
        keep = tracked & noisy.kept
        head_position, head_yaw = noisy.head_position, noisy.head_yaw
        if head_position is not None:
            head_position[hidden] = np.nan
            head_yaw[hidden] = np.nan
            head_position, head_yaw = head_position[keep], head_yaw[keep]
        ids = frame.ids[keep]
        return frame.replace(
            ids=ids,
            kinds=tuple(k for k, kept in zip(frame.kinds, keep, strict=True) if kept),
            position=noisy.position[keep],
            yaw=noisy.yaw[keep],
            head_position=head_position,
            head_yaw=head_yaw,
            groups=restrict_groups(frame.groups, set(ids.tolist())),
        )


@dataclass(frozen=True)
class Perturbation:
    """A tracker's errors, applied frame by frame: :class:`TrackerNoise` on whole frames.

    Attributes:
        position_noise: standard deviation of the noise on each position coordinate, metres.
        yaw_noise: standard deviation of the noise on each yaw, radians.
        dropout: probability that a person is missing from a frame, in [0, 1].
        perturb_robots: whether robots get noise and dropouts too (default: they know their
            pose).
    """

    position_noise: float = 0.0
    yaw_noise: float = 0.0
    dropout: float = 0.0
    perturb_robots: bool = False

    def __post_init__(self) -> None:
        levels = ("position_noise", "yaw_noise")
        check_levels(self, f"{type(self).__name__}.", levels, probabilities=("dropout",))
        object.__setattr__(self, "perturb_robots", bool(self.perturb_robots))

    @property
    def noise(self) -> TrackerNoise:
        """The noise model at these levels."""
        return TrackerNoise(
            position_std=self.position_noise, yaw_std=self.yaw_noise, dropout=self.dropout
        )

    @property
    def is_identity(self) -> bool:
        """True when applying it changes nothing."""
        return self.noise.is_identity

    def apply(self, frame: Frame, rng: np.random.Generator) -> Frame:
        """The frame as the imperfect tracker reports it.

        Args:
            frame: the true frame (not modified).
            rng: the generator; every call draws ``6 n`` numbers for a frame of ``n`` people
                (see the module docstring), whatever the levels.

        Returns:
            A new frame: the people kept, with noisy poses, and the ground truth restricted to
            them (``listed_groups`` kept, see the module docstring).
        """
        if not isinstance(frame, Frame):
            raise ValueError(f"frame must be a reform.Frame, got {type(frame).__name__}")
        affected = np.ones(frame.n_people, dtype=bool) if self.perturb_robots else None
        return self.noise.apply(frame, rng, affected=affected)

    def apply_all(self, frames: Iterable[Frame], rng: np.random.Generator) -> list[Frame]:
        """:meth:`apply` to each frame in turn, with one generator."""
        return [self.apply(frame, rng) for frame in frames]

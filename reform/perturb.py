"""Tracking errors applied to frames: position noise, orientation noise, dropped people.

A :class:`Perturbation` turns a frame into what an imperfect tracker would report: Gaussian noise
on every person's ground-plane position (metres per axis) and body yaw (radians), and each person
missed with a probability (a *dropout*: they vanish from the frame). It works on any
:class:`reform.Frame`, real or simulated, so the same stress test runs on SALSA as on a synthetic
party.

Conventions:
    * Robots are left as they are (a robot knows its own pose) unless ``perturb_robots`` is set.
    * Head poses, where present, get the same kind of noise as the body, drawn separately, and
      disappear with their person.
    * The ground truth of a perturbed frame is the original one restricted to the people still
      in it (a group of which one member remains becomes that member alone), as a tracker's
      output would be annotated; the detector is not blamed for people it was never given.
    * **Common random numbers.** For every frame the draws are made for every person in a fixed
      order, whatever the levels: standard normals for position (n, 2), head position (n, 2),
      yaw (n,), head yaw (n,), then uniforms (n,) for dropouts. The noise at level ``s`` is
      ``s`` times the same standard normal, and the people dropped at rate ``p`` are those whose
      uniform is below ``p``, so a generator seeded alike gives nested dropouts and noise that
      only grows along a sweep: curves over the levels differ by the level, not by the luck of
      the draw.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from reform.frame import Frame, Group, wrap_angle

__all__ = ["Perturbation", "restrict_groups"]


def restrict_groups(
    groups: tuple[Group, ...] | None, kept_ids: Iterable[int]
) -> tuple[Group, ...] | None:
    """``groups`` with only the members in ``kept_ids``; groups left empty are dropped."""
    if groups is None:
        return None
    kept = {int(i) for i in kept_ids}
    out = []
    for group in groups:
        members = tuple(m for m in group if m in kept)
        if members:
            out.append(members)
    return tuple(out)


def _level(name: str, value: float, *, high: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"Perturbation.{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value) or value < 0.0 or (high is not None and value > high):
        bound = f"in [0, {high:g}]" if high is not None else ">= 0 and finite"
        raise ValueError(f"Perturbation.{name} must be {bound}, got {value!r}")
    return value


@dataclass(frozen=True)
class Perturbation:
    """A tracker's errors, applied frame by frame.

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
        object.__setattr__(self, "position_noise", _level("position_noise", self.position_noise))
        object.__setattr__(self, "yaw_noise", _level("yaw_noise", self.yaw_noise))
        object.__setattr__(self, "dropout", _level("dropout", self.dropout, high=1.0))
        object.__setattr__(self, "perturb_robots", bool(self.perturb_robots))

    @property
    def is_identity(self) -> bool:
        """True when applying it changes nothing."""
        return self.position_noise == 0.0 and self.yaw_noise == 0.0 and self.dropout == 0.0

    def apply(self, frame: Frame, rng: np.random.Generator) -> Frame:
        """The frame as the imperfect tracker reports it.

        Args:
            frame: the true frame (not modified).
            rng: the generator; every call draws ``6 n`` numbers for a frame of ``n`` people
                (see the module docstring), whatever the levels.

        Returns:
            A new frame: the people kept, with noisy poses, and the ground truth restricted to
            them.
        """
        if not isinstance(frame, Frame):
            raise ValueError(f"frame must be a reform.Frame, got {type(frame).__name__}")
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        n = frame.n_people
        position_z = rng.standard_normal((n, 2))
        head_position_z = rng.standard_normal((n, 2))
        yaw_z = rng.standard_normal(n)
        head_yaw_z = rng.standard_normal(n)
        uniform = rng.random(n)
        affected = np.ones(n, dtype=bool) if self.perturb_robots else ~frame.is_robot
        keep = ~(affected & (uniform < self.dropout))
        noisy = affected[:, None]
        position = frame.position + np.where(noisy, position_z * self.position_noise, 0.0)
        yaw = wrap_angle(frame.yaw + np.where(affected, yaw_z * self.yaw_noise, 0.0))
        head_position = head_yaw = None
        if frame.head_position is not None:
            head_position = frame.head_position + np.where(
                noisy, head_position_z * self.position_noise, 0.0
            )
            head_yaw = np.where(
                np.isnan(frame.head_yaw),
                np.nan,
                wrap_angle(frame.head_yaw + np.where(affected, head_yaw_z * self.yaw_noise, 0.0)),
            )
            head_position = head_position[keep]
            head_yaw = head_yaw[keep]
        ids = frame.ids[keep]
        return frame.replace(
            ids=ids,
            kinds=tuple(k for k, kept in zip(frame.kinds, keep, strict=True) if kept),
            position=position[keep],
            yaw=yaw[keep],
            head_position=head_position,
            head_yaw=head_yaw,
            groups=restrict_groups(frame.groups, ids.tolist()),
        )

    def apply_all(self, frames: Iterable[Frame], rng: np.random.Generator) -> list[Frame]:
        """:meth:`apply` to each frame in turn, with one generator."""
        return [self.apply(frame, rng) for frame in frames]

"""The checks every detector must pass, as scikit-learn's ``check_estimator`` runs over estimators.

A detector is any object with ``predict(frames)`` (`reform.detectors.Detector`). Whatever it
does inside, the field's protocol asks the same of its answers, and so do these checks:

- **a partition per frame**: every person of the frame in exactly one group, one partition per
  frame, in order (`reform.detectors.check_predictions`);
- **no frames, nobody, one person**: an empty batch gives no partitions, a frame with nobody in
  it an empty partition, a frame of one person that person alone;
- **the same answer twice**: predicting the same frames again gives the same groups;
- **relabelling**: other ids for the same people, and the people listed in another order, give
  the same groups of the same people;
- **rigid motion**: the scene turned and moved on the floor (positions and orientations
  together) gives the same groups.

The scenes are circles of people facing their centre with a few people alone
(:func:`circle_frames`): clear enough that any sensible detector finds the groups, so that an
answer that changes under relabelling or motion says something about the detector, not the
scene.

Use::

    from reform.detector_checks import check_detector
    check_detector("mylab.detectors:make")          # a name, a plugin path, or a detector
    check_detector(my_detector, name="mine")

and in a test suite, one test per check (as ``parametrize_with_checks``)::

    @pytest.mark.parametrize("check", DETECTOR_CHECKS, ids=lambda c: c.__name__)
    def test_my_detector(check):
        check("mine", make())
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from reform.detectors import DetectorError, make_detector, run_detector
from reform.frame import Frame, Group, wrap_angle

__all__ = [
    "DETECTOR_CHECKS",
    "DetectorCheckError",
    "check_detector",
    "check_scenes",
    "circle_frame",
    "circle_frames",
]

GROUP_RADIUS_M = 0.6  # metres, centre to member of a circle
SPACING_M = 3.0  # metres between the centres of neighbouring circles (and people alone)
POSITION_NOISE_M = 0.08  # metres
YAW_NOISE_RAD = 0.25  # radians
CHECK_SEED = 20200  # the seed of the checks' scenes
# The rigid motions tried: (shift in metres, turn in radians).
MOTIONS = (
    ((0.0, 0.0), math.pi / 2),
    ((12.5, -40.0), 0.0),
    ((-3.0, 7.0), 2.0),
    ((100.0, 0.5), -2.9),
)


class DetectorCheckError(DetectorError):
    """A detector that fails one of the checks: one line naming the detector and the check."""


def circle_frame(
    rng: np.random.Generator,
    *,
    sizes: Sequence[int] = (3, 2, 4),
    loners: int = 2,
    time: float = 0.0,
    sequence: str = "circles",
    first_id: int = 1,
) -> Frame:
    """A frame with one circular F-formation per entry of ``sizes`` and ``loners`` people alone,
    on a grid ``SPACING_M`` apart, with a little noise on every position and orientation."""
    positions, yaws, groups = [], [], []
    person = first_id
    n_spots = len(sizes) + loners
    side = int(np.ceil(np.sqrt(n_spots)))
    spots = rng.permutation(side * side)[:n_spots]
    centres = np.stack([spots % side, spots // side], axis=1) * SPACING_M
    for centre, size in zip(centres[: len(sizes)], sizes, strict=True):
        angles = rng.uniform(0, 2 * np.pi) + np.arange(size) * 2 * np.pi / size
        ring = centre + GROUP_RADIUS_M * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        positions.append(ring + rng.normal(0, POSITION_NOISE_M, ring.shape))
        yaws.append(angles + np.pi + rng.normal(0, YAW_NOISE_RAD, size))
        groups.append(tuple(range(person, person + size)))
        person += size
    for centre in centres[len(sizes) :]:
        positions.append(centre[None] + rng.normal(0, 0.3, (1, 2)))
        yaws.append(rng.uniform(-np.pi, np.pi, 1))
        person += 1
    n = person - first_id
    position = np.concatenate(positions) if positions else np.zeros((0, 2))
    yaw = np.concatenate(yaws) if yaws else np.zeros(0)
    return Frame(
        ids=np.arange(first_id, first_id + n),
        position=position,
        yaw=wrap_angle(yaw),
        groups=tuple(groups),
        time=time,
        sequence=sequence,
    )


def circle_frames(seed: int, count: int, **kwargs: Any) -> list[Frame]:
    """``count`` frames of :func:`circle_frame` from one seed, at times 0, 1, 2, ... seconds."""
    rng = np.random.default_rng(seed)
    return [circle_frame(rng, time=float(t), **kwargs) for t in range(count)]


def check_scenes() -> list[Frame]:
    """The frames every check runs on: six frames of circles and people alone."""
    return circle_frames(CHECK_SEED, 4, sizes=(3, 2, 4), loners=2) + circle_frames(
        CHECK_SEED + 1, 2, sizes=(2, 5), loners=1
    )


def _as_sets(partition: Sequence[Group]) -> set[frozenset[int]]:
    return {frozenset(int(m) for m in group) for group in partition}


def _fail(name: str, check: str, what: str) -> DetectorCheckError:
    return DetectorCheckError(f"{name}: fails {check}: {what}")


def check_partition_per_frame(name: str, detector: Any) -> None:
    """One partition of each frame's people per frame, in order (`run_detector` checks it)."""
    frames = check_scenes()
    run_detector(name, detector, frames)


def check_no_frames_nobody_and_one_person(name: str, detector: Any) -> None:
    """No frames: no partitions; nobody: an empty partition; one person: that person alone.

    `run_detector` refuses any other answer (one partition per frame, each a partition of
    exactly the frame's people), naming the frame and what came back.
    """
    run_detector(name, detector, [])
    sequence = check_scenes()[0].sequence  # the scenes' recording, so that per-sequence
    # settings (gcff-own) cover these frames too
    nobody = Frame(
        ids=np.zeros(0, np.int64), position=np.zeros((0, 2)), yaw=np.zeros(0), sequence=sequence
    )
    one = Frame(
        ids=np.array([7]),
        position=np.array([[1.0, 2.0]]),
        yaw=np.array([0.5]),
        sequence=sequence,
        time=1.0,
    )
    run_detector(name, detector, [nobody, one])


def check_the_same_answer_twice(name: str, detector: Any) -> None:
    """The same frames predicted twice give the same groups."""
    frames = check_scenes()
    first = [_as_sets(p) for p in run_detector(name, detector, frames)]
    again = [_as_sets(p) for p in run_detector(name, detector, frames)]
    for k, (a, b) in enumerate(zip(first, again, strict=True)):
        if a != b:
            raise _fail(name, "the same answer twice", f"frame {k}: {_show(a)} then {_show(b)}")


def check_relabelling(name: str, detector: Any) -> None:
    """Other ids for the same people, listed in another order, give the same groups.

    A person keeps one id through a sequence (a detector that follows people over time may rely
    on it), so each sequence's ids are mapped once; each frame lists its people in a new order.
    """
    frames = check_scenes()
    rng = np.random.default_rng(CHECK_SEED)
    before = [_as_sets(p) for p in run_detector(name, detector, frames)]
    relabelled, back = [], []
    mappings: dict[str, dict[int, int]] = {}
    for frame in frames:
        order = rng.permutation(frame.n_people)
        mapping = mappings.setdefault(frame.sequence, {})
        for person in frame.ids.tolist():
            while person not in mapping:
                new = int(rng.integers(10**6)) + 1000
                if new not in mapping.values():
                    mapping[person] = new
        new_ids = np.array([mapping[person] for person in frame.ids.tolist()], dtype=np.int64)
        mapping = {person: mapping[person] for person in frame.ids.tolist()}
        relabelled.append(
            Frame(
                ids=new_ids[order],
                position=frame.position[order],
                yaw=frame.yaw[order],
                groups=tuple(tuple(mapping[m] for m in g) for g in frame.groups or ()),
                time=frame.time,
                sequence=frame.sequence,
            )
        )
        back.append({new: old for old, new in mapping.items()})
    after = run_detector(name, detector, relabelled)
    for k, (expected, partition, inverse) in enumerate(zip(before, after, back, strict=True)):
        found = {frozenset(inverse[int(m)] for m in group) for group in partition}
        if found != expected:
            raise _fail(name, "relabelling", f"frame {k}: {_show(expected)} became {_show(found)}")


def check_rigid_motion(name: str, detector: Any) -> None:
    """The scene turned and moved on the floor gives the same groups."""
    frames = check_scenes()
    before = [_as_sets(p) for p in run_detector(name, detector, frames)]
    for shift, turn in MOTIONS:
        rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
        moved = [
            f.replace(position=f.position @ rotation.T + shift, yaw=wrap_angle(f.yaw + turn))
            for f in frames
        ]
        after = [_as_sets(p) for p in run_detector(name, detector, moved)]
        for k, (a, b) in enumerate(zip(before, after, strict=True)):
            if a != b:
                raise _fail(
                    name,
                    "rigid motion",
                    f"frame {k} turned {turn:g} rad and moved by {shift} m: {_show(a)} became "
                    f"{_show(b)}",
                )


def _show(partition: set[frozenset[int]]) -> str:
    groups = sorted(sorted(g) for g in partition if len(g) > 1)
    text = str([tuple(g) for g in groups])
    return text if len(text) <= 200 else text[:200] + "…"


DETECTOR_CHECKS: tuple[Callable[[str, Any], None], ...] = (
    check_partition_per_frame,
    check_no_frames_nobody_and_one_person,
    check_the_same_answer_twice,
    check_relabelling,
    check_rigid_motion,
)


def check_detector(detector: Any, *, name: str | None = None, **options: Any) -> None:
    """Runs every check of :data:`DETECTOR_CHECKS` on ``detector``.

    Args:
        detector: a detector (an object with ``predict``), or a name or plugin path that
            `reform.make_detector` makes with ``options``.
        name: the detector's name in messages (default: the name given, or its class).
        **options: the factory's options, when ``detector`` is a name.

    Raises:
        DetectorError: one line naming the detector, the check it fails and the frame.
    """
    if isinstance(detector, str):
        name = name or detector
        detector = make_detector(detector, **options)
    elif options:
        raise ValueError("options are for a detector given by name; this one is already made")
    name = name or type(detector).__name__
    for check in DETECTOR_CHECKS:
        check(name, detector)

"""The stress tests' axes and grids: what `reform-sim stress` can vary, and by how much.

Kept apart from :mod:`sim.experiments.stress` (which runs the tests) so that the command line can
list the axes and grids without loading MuJoCo or scikit-learn.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass
from numbers import Integral
from types import MappingProxyType
from typing import Any

__all__ = [
    "AXES",
    "BASE_PEOPLE",
    "CROWD_MAX_PEOPLE",
    "CROWD_MIN_PEOPLE",
    "GRIDS",
    "SENSOR_NAMES",
    "StressGrid",
    "check_axis",
    "resolve_grid",
]

BASE_PEOPLE = 18  # guests of the test party (SALSA: 18)
# People of the crowd axis's concourse: the range of the scenario's option people.
CROWD_MIN_PEOPLE, CROWD_MAX_PEOPLE = 50, 3000
# The sensor levels, in order (`sim.experiments.stress.SENSORS` holds their sensor models): the
# ground truth of everyone in the room, then the robot's head sensor with field of view and range
# only, with occlusion, and with occlusion and tracking errors.
SENSOR_NAMES = ("truth", "fov", "occlusion", "tracker")


@dataclass(frozen=True)
class _AxisInfo:
    name: str
    title: str
    x_label: str
    kind: str  # "perturb" (applied to the base episodes) or "scene" (a new episode per level)
    description: str


AXES: Mapping[str, _AxisInfo] = MappingProxyType(
    {
        info.name: info
        for info in (
            _AxisInfo(
                "position-noise",
                "Position noise",
                "position noise (m, sd per axis)",
                "perturb",
                "Gaussian noise on every person's position, standard deviation per axis.",
            ),
            _AxisInfo(
                "orientation-noise",
                "Orientation noise",
                "orientation noise (deg, sd)",
                "perturb",
                "Gaussian noise on every person's body (and head) yaw.",
            ),
            _AxisInfo(
                "dropout",
                "Tracking dropout",
                "dropout (share of people missed per frame)",
                "perturb",
                "Each person missing from each frame independently with this probability; the "
                "truth is restricted to the people kept.",
            ),
            _AxisInfo(
                "density",
                "Crowd density",
                "density (guests per m²)",
                "scene",
                f"{BASE_PEOPLE} guests in a square room whose side gives this density.",
            ),
            _AxisInfo(
                "groups",
                "Number of groups",
                "guests (at 0.4 per m²)",
                "scene",
                "More guests at the default density: more groups at once (see F-formations "
                "per frame).",
            ),
            _AxisInfo(
                "group-size",
                "Size of groups",
                "largest group allowed (people)",
                "scene",
                "The party's largest group (mingle's max_group_size); see the mean F-formation "
                "size.",
            ),
            _AxisInfo(
                "sensor",
                "Sensor",
                "sensor (0 truth, 1 field of view, 2 + occlusion, 3 + tracking errors)",
                "scene",
                "The party with the robot watching from the west wall, seen from the ground "
                "truth or by the robot's head sensor.",
            ),
            _AxisInfo(
                "crowd",
                "Crowd size",
                "people in the concourse",
                "scene",
                "The concourse (scenarios.concourse) with this many people in its hall: walkers "
                "crossing, a queue, groups standing aside in the corners (the ground truth's only "
                "groups).",
            ),
            _AxisInfo(
                "event-rate",
                "Scripted changes",
                "scripted changes per minute",
                "scene",
                "The party with scripted changes on top of its own comings and goings "
                "(mingle's event_rate): latecomers walking up to groups, members drifting "
                "away, groups walking over to merge.",
            ),
        )
    }
)


def _floats(name: str, values: Iterable[Any], *, low: float, high: float) -> tuple[float, ...]:
    out = []
    for value in values:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"StressGrid.{name} must hold numbers, got {value!r}")
        if not (math.isfinite(value) and low <= value <= high):
            raise ValueError(
                f"StressGrid.{name} values must lie in [{low:g}, {high:g}], got {value}"
            )
        out.append(float(value))
    return tuple(out)


def _ints(name: str, values: Iterable[Any], *, low: int, high: int) -> tuple[int, ...]:
    out = []
    for value in values:
        if isinstance(value, bool) or not isinstance(value, Integral):
            raise ValueError(f"StressGrid.{name} must hold integers, got {value!r}")
        if not low <= value <= high:
            raise ValueError(f"StressGrid.{name} values must lie in [{low}, {high}], got {value}")
        out.append(int(value))
    return tuple(out)


MAX_STRESS_EPISODES = 10**6  # test episodes per point

# StressGrid's fields: name, kind (a tuple of floats or ints, or one float or int), bounds.
_GRID_FIELDS = (
    ("position_noise_m", "floats", 0.0, 5.0),
    ("orientation_noise_deg", "floats", 0.0, 360.0),
    ("dropout", "floats", 0.0, 1.0),
    ("density_per_m2", "floats", 0.01, 1.0),
    ("people", "ints", 2, 100),
    ("max_group_size", "ints", 2, 12),
    ("crowd_people", "ints", CROWD_MIN_PEOPLE, CROWD_MAX_PEOPLE),
    ("event_rate_per_min", "floats", 0.0, 20.0),
    ("seeds", "int", 1, MAX_STRESS_EPISODES),
    ("duration_s", "float", 1e-3, 1e6),
    ("rate_hz", "float", 1e-3, 1e3),
    ("train_episodes", "int", 1, 10**6),
    ("train_duration_s", "float", 1e-3, 1e6),
    ("train_rate_hz", "float", 1e-3, 1e3),
    ("resamples", "int", 1, 10**7),
    ("gcff_stride_grid_m", "floats", 0.0, 10.0),
    ("gcff_mdl_grid_m2", "floats", 1e-6, 1e3),
    ("gcff_tuning_frames", "int", 1, 10**7),
)


@dataclass(frozen=True)
class StressGrid:
    """The levels of every axis and the size of the run.

    Attributes:
        position_noise_m: position noise levels, metres (0-0.5).
        orientation_noise_deg: orientation noise levels, degrees (0-60).
        dropout: dropout levels, shares (0-0.5).
        density_per_m2: guests per m² (mingle's planner lays out 18 guests up to about 0.5).
        people: numbers of guests at the default density.
        max_group_size: largest groups allowed (2-12).
        crowd_people: people in the concourse of the crowd axis (50-3,000).
        sensors: sensor levels, names of :data:`SENSOR_NAMES`.
        event_rate_per_min: scripted changes per minute of the party (0-20; mingle's
            ``event_rate``).
        seeds: test episodes per point.
        duration_s: length of a test episode, seconds.
        rate_hz: frames per second scored.
        train_episodes: training episodes per training scenario.
        train_duration_s: length of a training episode, seconds.
        train_rate_hz: frames per second of the training set.
        resamples: bootstrap resamples per point.
        gcff_stride_grid_m: strides GCFF is tuned over, metres.
        gcff_mdl_grid_m2: mdl values GCFF is tuned over, square metres.
        gcff_tuning_frames: training frames GCFF is tuned on at most (evenly subsampled).
    """

    position_noise_m: tuple[float, ...] = (0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5)
    orientation_noise_deg: tuple[float, ...] = (0.0, 10.0, 20.0, 30.0, 45.0, 60.0)
    dropout: tuple[float, ...] = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5)
    density_per_m2: tuple[float, ...] = (0.1, 0.2, 0.3, 0.4, 0.5)
    people: tuple[int, ...] = (6, 12, 18, 30, 48)
    max_group_size: tuple[int, ...] = (2, 3, 4, 6, 8, 12)
    crowd_people: tuple[int, ...] = (100, 300, 1000)
    sensors: tuple[str, ...] = SENSOR_NAMES
    event_rate_per_min: tuple[float, ...] = (0.0, 2.0, 4.0, 8.0, 12.0)
    seeds: int = 5
    duration_s: float = 600.0
    rate_hz: float = 0.5
    train_episodes: int = 4
    train_duration_s: float = 600.0
    train_rate_hz: float = 0.5
    resamples: int = 1000
    gcff_stride_grid_m: tuple[float, ...] = (0.5, 0.6, 0.7, 0.8)
    gcff_mdl_grid_m2: tuple[float, ...] = (0.5, 1.0, 2.0, 3.0)
    gcff_tuning_frames: int = 600

    def __post_init__(self) -> None:
        for name, kind, low, high in _GRID_FIELDS:
            value = getattr(self, name)
            if kind == "floats":
                value = _floats(name, value, low=low, high=high)
            elif kind == "ints":
                value = _ints(name, value, low=int(low), high=int(high))
            elif kind == "int":
                (value,) = _ints(name, [value], low=int(low), high=int(high))
            else:
                (value,) = _floats(name, [value], low=low, high=high)
            if kind in ("floats", "ints") and not value:
                raise ValueError(f"StressGrid.{name} must hold at least one level, got none")
            object.__setattr__(self, name, value)
        sensors = tuple(self.sensors)
        unknown = [s for s in sensors if s not in SENSOR_NAMES]
        if unknown or not sensors:
            raise ValueError(f"StressGrid.sensors must be names of {SENSOR_NAMES}, got {sensors}")
        object.__setattr__(self, "sensors", sensors)

    def levels(self, axis: str) -> tuple[Any, ...]:
        """The levels of ``axis`` (one of :data:`AXES`)."""
        return {
            "position-noise": self.position_noise_m,
            "orientation-noise": self.orientation_noise_deg,
            "dropout": self.dropout,
            "density": self.density_per_m2,
            "groups": self.people,
            "group-size": self.max_group_size,
            "sensor": self.sensors,
            "crowd": self.crowd_people,
            "event-rate": self.event_rate_per_min,
        }[check_axis(axis)]

    def to_json(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


GRIDS: Mapping[str, StressGrid] = MappingProxyType(
    {
        "default": StressGrid(),
        "small": StressGrid(
            position_noise_m=(0.0, 0.25, 0.5),
            orientation_noise_deg=(0.0, 30.0, 60.0),
            dropout=(0.0, 0.25, 0.5),
            density_per_m2=(0.2, 0.4),
            people=(6, 18),
            max_group_size=(3, 8),
            crowd_people=(60, 150),
            sensors=("truth", "occlusion"),
            event_rate_per_min=(0.0, 8.0),
            seeds=2,
            duration_s=40.0,
            rate_hz=0.5,
            train_episodes=1,
            train_duration_s=120.0,
            train_rate_hz=0.5,
            resamples=200,
            gcff_stride_grid_m=(0.7,),
            gcff_mdl_grid_m2=(1.0,),
            gcff_tuning_frames=60,
        ),
    }
)


def resolve_grid(grid: StressGrid | str) -> tuple[str, StressGrid]:
    """A grid and its name: ``grid`` itself or the grid of :data:`GRIDS` it names.

    Returns:
        The name (that of the equal grid of :data:`GRIDS`, else ``"custom"``) and the grid.
    """
    if isinstance(grid, str):
        if grid not in GRIDS:
            raise ValueError(f"grid must be one of {tuple(GRIDS)} or a StressGrid, got {grid!r}")
        return grid, GRIDS[grid]
    if not isinstance(grid, StressGrid):
        raise ValueError(f"grid must be a StressGrid or a name, got {type(grid).__name__}")
    return next((n for n, g in GRIDS.items() if g == grid), "custom"), grid


def check_axis(axis: str) -> str:
    """``axis`` when it names one of :data:`AXES`; ValueError listing them otherwise."""
    if axis not in AXES:
        raise ValueError(f"axis must be one of {tuple(AXES)}, got {axis!r}")
    return axis

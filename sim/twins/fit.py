"""Fitting a venue twin to a recording's frames, without their groups.

The recipe (`fit_twin`), each step matching one label-free statistic of the real frames
(`sim.twins.statistics.measure_place`) with the same statistic of short simulated parties:

1. **people**: ``mingle``'s ``people`` is the median number of humans per frame, its
   ``max_group_size`` no more than them. A crowd larger than a ``mingle`` party holds (its
   ``people`` range) is a ``concourse`` (`CROWD`; `venue_for`): as many people in a frame as the
   recording (walkers go out and come back, so the scene holds more), the share standing still
   (`sim.twins.statistics.standing_share`) in its corners and everyone else walking through (a
   queue is not told apart from people standing aside: none), its hall sized as a party's room
   is, and its largest group searched on the shape of the crowd (`CROWD_CHOICES`), with shorter
   pilots (`CROWD_PILOT_EPISODES` of `CROWD_PILOT_S`). A crowd larger than the concourse's is
   refused;
2. **rate and length**: frames at the recording's rate, episodes as long as its sequences (cut so
   that at least `MIN_EPISODES` episodes make `TARGET_FRAMES` frames or so);
3. **spacing and scale**: pilot parties are simulated (`PILOT_EPISODES` of `PILOT_S` seconds);
   the annotation's fixed ``scale`` is the real median nearest-neighbour distance over the
   pilot's, and the room's side is set so that the box holding everyone, scaled, is as large as
   the real one (crowding); `PILOT_ROUNDS` rounds of both; before them, the crowd's shape
   (`SHAPE_CHOICES`: spacing, largest group, unevenness, share alone, arrangements, noise on
   facings) is searched one option at a time, `SHAPE_PASSES` passes, each choice kept where
   the pilot's `sim.twins.statistics.spacing_shape` and `sim.twins.statistics.detector_shape`
   come closest to the recording's (nearest-neighbour distances, facing away from the nearest,
   facing a common point, clumps of bodies and of o-space votes; how fixed detectors group the
   people and how much they agree, on the pilot scaled to the recording's spacing);
4. **orientation coding**: the number of directions every real yaw is coded in (continuous
   when none fits), the head's yaw when the recording's yaw is its head's;
5. **tracker**: position and yaw jitter on top of the pilot's own, so that people standing still
   move between frames as much as in the recording; dropouts at the recording's rate.

With ``use_labels`` (a separate mode, recorded in the twin), the annotated frames also fix the
group structure: the share of people alone, the largest group and the o-space radius law
(least squares on the mean distance of members to their group's centre by size).
Every frame's groups are removed before anything else in the label-free mode, so the twin
cannot depend on them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from reform.annotation import AnnotationModel
from reform.frame import Frame
from reform.seeding import derive_int, derive_rng
from scenarios.concourse import MIN_HALL_M
from scenarios.mingle import MAX_DENSITY_PER_M2, MIN_ROOM_M, NoFloorError
from sim.twins.description import Fitted, Twin
from sim.twins.statistics import (
    SHAPE_SIZE,
    SHORT_STRIDE_M,
    PlaceStatistics,
    detector_shape,
    measure_place,
    nearest_neighbour_distances,
    spacing_shape,
    standing_share,
)

__all__ = [
    "MIN_FRAMES",
    "TwinInputError",
    "check_frames_for_twin",
    "fit_twin",
    "room_for_every_episode",
    "twin_sample",
]

SCENARIO = "mingle"  # a party: the scenario of a twin
CROWD = "concourse"  # ... of a crowd larger than a party holds (`mingle`'s most people)
MIN_FRAMES = 10  # frames a recording needs to be fitted
NN_RANGE_M = (0.05, 20.0)  # metres: a median nearest neighbour outside says the unit is wrong
TARGET_FRAMES = 1200  # frames of a generated twin, about (at least the recording's, at most)
MIN_TARGET_FRAMES = 400
MIN_EPISODES = 4
MAX_EPISODES = 40
EPISODE_S = (30.0, 600.0)  # seconds, shortest and longest episode
PILOT_EPISODES = 3
PILOT_S = 120.0  # seconds per pilot episode
PILOT_RATE_HZ = 0.5
PILOT_ROUNDS = 3
AGREEMENT_WEIGHT = 8.0  # of the detectors' agreement in the shape distance
SHAPE_PASSES = 2  # passes over the crowd options searched one at a time
MAX_ROOM_M = 100.0  # metres: the simulator's largest room (`sim.scene.ROOM_MAX_M`)
ROOM_GROWTH = 1.1  # a room the party does not fit grows by this factor
ROOM_TRIES = 12
MAX_GROUP = 8  # mingle's default largest group
STEP_S = 0.01  # seconds: the simulator's control step; a frame is a whole number of them
PILOT, CHECK, SHAPE = 11, 12, 13  # seed roles of the pilot and of the twin's own figures


# The crowd options searched label-free, in this order, one at a time (mingle's own ranges;
# ``max_group_size`` no more than the people).
SHAPE_CHOICES: Mapping[str, tuple[Any, ...]] = MappingProxyType(
    {
        "spacing": (0.63, 0.5, 0.43),  # metres: how close two people may stand
        "max_group_size": (3, 5, 8),  # largest group
        "unevenness": (0.0, 0.5, 1.0),  # how unevenly members spread round the o-space
        "alone_share": (0.08, 0.25, 0.5),  # share of people alone at the start
        "arrangements": (0.0, 0.5),  # share of groups side by side or presenter and audience
        "orientation_noise": (0.1, 0.2, 0.35, 0.5, 0.7, 1.0),  # radians: facing off the centre
    }
)
CROWD_CHOICES: Mapping[str, tuple[Any, ...]] = MappingProxyType(
    {"max_group_size": (3, 5, 8)}  # the concourse's corners hold mingle's parties
)
CROWD_PILOT_EPISODES = 1  # a crowd's pilot holds hundreds of people: one episode says enough
CROWD_PILOT_S = 60.0  # seconds


@dataclass(frozen=True)
class Venue:
    """What the fit needs of the scenario a twin enacts.

    Attributes:
        scenario: the registered scenario.
        room: its option sizing the floor (a square's side, metres).
        least_room: the smallest floor's side, metres.
        choices: the crowd options searched on the shape of the crowd, in order.
        pilot_episodes: episodes of a pilot.
        pilot_s: seconds of each.
    """

    scenario: str
    room: str
    least_room: float
    choices: Mapping[str, tuple[Any, ...]]
    pilot_episodes: int = PILOT_EPISODES
    pilot_s: float = PILOT_S


VENUES: Mapping[str, Venue] = MappingProxyType(
    {
        SCENARIO: Venue(SCENARIO, "room_side", MIN_ROOM_M, SHAPE_CHOICES),
        CROWD: Venue(
            CROWD, "hall_side", MIN_HALL_M, CROWD_CHOICES, CROWD_PILOT_EPISODES, CROWD_PILOT_S
        ),
    }
)


def people_range(scenario: str) -> tuple[int, int]:
    """The fewest and most people ``scenario``'s ``people`` option allows (its registry range)."""
    import scenarios

    declared = next(o for o in scenarios.registry.options(scenario) if o.name == "people")
    return int(declared.range.low), int(declared.range.high)


def venue_for(people: float) -> Venue:
    """The party (`SCENARIO`) for ``people`` (humans per frame, median) a party holds, else the
    crowd (`CROWD`)."""
    return VENUES[SCENARIO if round(people) <= people_range(SCENARIO)[1] else CROWD]


SHAPE_STATISTIC = (
    "spacing shape: nearest-neighbour q10, q25, q75, q90, 2nd and 3rd nearest over the median "
    "nearest neighbour, share standing apart, facing away from the nearest (median, q75, rad), "
    "a person and the nearest off facing a common point (q25, median, q75, rad), clumps "
    "(mean size, share in clumps of 4 or more), o-space votes (share alone, mean clump size); "
    f"detectors: share GCFF groups, its mean group size, F1 of GCFF at a {SHORT_STRIDE_M:g} m "
    "stride and of proximity against GCFF's groups"
)


class TwinInputError(ValueError):
    """A recording a twin cannot be fitted to: one line naming file, field, expected, found."""


def _strip(frames: Sequence[Frame]) -> list[Frame]:
    return [f if f.groups is None else f.replace(groups=None, listed_groups=None) for f in frames]


def check_frames_for_twin(frames: Sequence[Frame], *, where: str) -> None:
    """Refuses a recording too small to fit or in the wrong unit, before any work.

    Raises:
        TwinInputError: fewer than `MIN_FRAMES` frames, never two people at once, or a median
            nearest-neighbour distance outside `NN_RANGE_M`.
    """
    if len(frames) < MIN_FRAMES:
        raise TwinInputError(
            f"{where}: field frames: expected at least {MIN_FRAMES} frames to fit a twin, found "
            f"{len(frames)}"
        )
    most = max((int(np.sum(~f.is_robot)) for f in frames), default=0)
    if most < 2:
        raise TwinInputError(
            f"{where}: field ids: expected two or more people in some frame, found at most {most}"
        )
    humans = float(np.median([int(np.sum(~f.is_robot)) for f in frames]))
    most = people_range(CROWD)[1]
    if round(humans) > most:
        raise TwinInputError(
            f"{where}: field ids: expected at most {most} humans per frame (median; the "
            f"{CROWD}'s largest crowd), found {humans:g}"
        )
    nn = float(np.median(nearest_neighbour_distances(frames)))
    low, high = NN_RANGE_M
    if not low <= nn <= high:
        raise TwinInputError(
            f"{where}: field position: expected a median nearest-neighbour distance of {low:g} to "
            f"{high:g} m, found {nn:.4g} (positions in another unit? convert them to metres)"
        )


def _room_for(venue: Venue, people: int, side: float) -> float:
    least = max(venue.least_room, math.sqrt(people / MAX_DENSITY_PER_M2) + 1e-6)
    return float(min(MAX_ROOM_M, max(least, side)))


def _simulate(
    options: dict[str, Any], *, seed: int, rate: float, venue: Venue = VENUES[SCENARIO]
) -> tuple[list[Frame], dict]:
    """Pilot episodes of ``options``; a room they do not fit grows (returned options)."""
    from sim.episode import simulate_episode

    options = dict(options)
    room = venue.room
    for _ in range(ROOM_TRIES):
        try:
            frames: list[Frame] = []
            for k in range(venue.pilot_episodes):
                episode = simulate_episode(
                    venue.scenario, seed=derive_int(seed, k), rate=rate, options=options
                )
                frames.extend(episode.dataset)
            return frames, options
        except NoFloorError:
            options[room] = _room_for(venue, options["people"], options[room] * ROOM_GROWTH)
    raise TwinInputError(
        f"twin: field options.{room}: expected a floor the crowd fits, found none up to "
        f"{options[room]:.3g} m"
    )


def room_for_every_episode(
    options: Mapping[str, Any], *, seed: int, episodes: int, scenario: str = SCENARIO
) -> dict[str, Any]:
    """``options`` with a room every episode of the twin's data fits (each episode's crowd is
    drawn, not simulated; the room grows by `ROOM_GROWTH` until all fit): the episodes
    ``episode_seed(seed, k)`` for k below ``episodes`` (at least `MIN_EPISODES`), as
    `sim.generate` seeds them."""
    import scenarios
    from sim.generate import episode_seed

    venue = VENUES[scenario]
    room = venue.room
    options = dict(options)
    for _ in range(ROOM_TRIES):
        try:
            for k in range(max(episodes, MIN_EPISODES)):
                scenarios.make(scenario, seed=episode_seed(seed, k), **options)
            return options
        except NoFloorError:
            side = _room_for(venue, options["people"], options[room] * ROOM_GROWTH)
            options[room] = float(f"{side:.6g}")
    raise TwinInputError(
        f"twin: field options.{room}: expected a floor every episode fits, found none up to "
        f"{options[room]:.3g} m"
    )


def _sample(
    options: Mapping[str, Any],
    annotation: AnnotationModel,
    *,
    seed: int,
    rate: float,
    venue: Venue = VENUES[SCENARIO],
) -> list[Frame]:
    frames, _ = _simulate(dict(options), seed=derive_int(seed, CHECK), rate=rate, venue=venue)
    return list(annotation.apply(frames, derive_rng(seed, CHECK)))


def twin_sample(twin: Twin) -> list[Frame]:
    """A few of the twin's frames, as its fit measured them (its venue's pilot episodes, seeded
    by the twin's seed): what ``twin.json``'s twin figures and the plots are made of."""
    return _sample(
        twin.options,
        twin.annotation,
        seed=twin.seed,
        rate=twin.rate_hz,
        venue=VENUES[twin.scenario],
    )


def _shape_distance(real: np.ndarray, twin: np.ndarray) -> float:
    """How far two signatures (`spacing_shape`, then `detector_shape`) are: squared log ratios
    of the six distance ratios and of the mean sizes of clumps and of vote clumps, plus the
    squared differences of the shares standing apart, in clumps of 4 or more and voting alone
    (each times 4), of the median angle a person faces away from their nearest neighbour
    (radians: back to back with a neighbouring group's member, or facing them in one o-space)
    and of the lower quartile and median of the angles off facing a common point (radians; the
    upper quartile is left to the people standing beside someone they do not face, whom the
    share voting alone counts, and not to the noise on facings); then, where the recording's
    detectors found anything, the squared difference of the shares GCFF groups (times 4), the
    squared log ratio of its mean group sizes and the squared differences of the detectors'
    agreements (times `AGREEMENT_WEIGHT`)."""
    ratios = np.log(np.maximum(twin[[*range(6), 12, 15]], 1e-6))
    ratios -= np.log(np.maximum(real[[*range(6), 12, 15]], 1e-6))
    facing = twin[[7, 9, 10]] - real[[7, 9, 10]]
    shares = twin[[6, 13, 14]] - real[[6, 13, 14]]
    distance = float(np.sum(ratios**2) + 4.0 * np.sum(shares**2) + np.sum(facing**2))
    if real.size > SHAPE_SIZE and np.all(np.isfinite(real[SHAPE_SIZE:])):
        r, t = real[SHAPE_SIZE:], twin[SHAPE_SIZE:]
        size = math.log(max(t[1], 1e-6) / max(r[1], 1e-6))
        distance += (
            4.0 * (t[0] - r[0]) ** 2 + size**2 + AGREEMENT_WEIGHT * np.sum((t[2:] - r[2:]) ** 2)
        )
    return distance if math.isfinite(distance) else math.inf  # a pilot that says nothing: last


def _pilot_signature(
    trial: dict[str, Any], real: PlaceStatistics, seed: int, scenario: str = SCENARIO
) -> np.ndarray:
    """The `_signature` of the pilot parties of the crowd options ``trial`` (a unit of work a
    worker process may run: each pilot is seeded by ``seed`` alone, wherever it runs)."""
    sim_frames, _ = _simulate(
        trial, seed=derive_int(seed, SHAPE), rate=PILOT_RATE_HZ, venue=VENUES[scenario]
    )
    return _signature(sim_frames, real, seed=seed)


def _fit_spacing_shape(
    frames: Sequence[Frame],
    real: PlaceStatistics,
    options: dict[str, Any],
    *,
    seed: int,
    n_jobs: int = 1,
    venue: Venue = VENUES[SCENARIO],
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The crowd options (the ``venue``'s choices, `SHAPE_CHOICES` for a party, one at a time in
    that order, each kept where it brings
    the pilot's `spacing_shape` closest to the recording's; `SHAPE_PASSES` passes, so that an
    option chosen early is chosen again beside the later ones) on a room sized once for the
    recording's crowding. ``n_jobs`` > 1: the choices of one option not yet tried run on that
    many processes at once (the same pilots, the same choices)."""
    target = np.concatenate([spacing_shape(frames), detector_shape(frames)])
    options = dict(options)
    if not np.all(np.isfinite(target[:SHAPE_SIZE])):
        return options, {}
    run = {**options, "duration": venue.pilot_s}
    sim_frames, run = _simulate(run, seed=derive_int(seed, SHAPE), rate=PILOT_RATE_HZ, venue=venue)
    pilot = measure_place(sim_frames)
    scale = real.nn_median / pilot.nn_median
    side = run[venue.room] * (real.extent_m / scale) / pilot.extent_m
    options[venue.room] = _room_for(venue, options["people"], side)
    best_shape = None
    seen: dict[tuple, tuple[float, np.ndarray]] = {}  # pilots already run, by their options
    executor = None
    if n_jobs > 1:
        from sim.executor import Executor

        executor = Executor("local", jobs=n_jobs, progress=False)
    for _ in range(SHAPE_PASSES):
        for key, choices in venue.choices.items():
            if key == "max_group_size":
                choices = tuple(sorted({min(c, options["people"]) for c in choices}))
            trials = [{**options, key: value, "duration": venue.pilot_s} for value in choices]
            keys = [tuple(sorted(trial.items())) for trial in trials]
            new = {k: t for k, t in zip(keys, trials, strict=True) if k not in seen}  # to run
            units = list(new.values())
            if executor is not None and len(units) > 1:
                signatures = executor.map(
                    _pilot_signature, units, shared=(real, seed, venue.scenario)
                )
            else:
                signatures = [
                    _pilot_signature(trial, real, seed, venue.scenario) for trial in units
                ]
            for known, signature in zip(new, signatures, strict=True):
                seen[known] = (_shape_distance(target, signature), signature)
            scores = [seen[known] for known in keys]
            k = min(range(len(choices)), key=lambda j: scores[j][0])
            options[key] = choices[k]
            best_shape = scores[k][1]
    shown = [float(f"{v:.4g}") for v in target]
    return options, {"real": shown, "twin": [float(f"{v:.4g}") for v in best_shape]}


def _signature(sim_frames: Sequence[Frame], real: PlaceStatistics, *, seed: int) -> np.ndarray:
    """A pilot's `spacing_shape` and `detector_shape`, its frames coded as the recording codes
    yaws and scaled to the recording's median nearest neighbour (the detectors run in
    metres)."""
    nn = nearest_neighbour_distances(sim_frames)
    scale = real.nn_median / float(np.median(nn)) if nn.size else 1.0
    coding = AnnotationModel(directions=real.directions or None, scale=scale)
    coded = coding.apply(sim_frames, derive_rng(seed, SHAPE))
    return np.concatenate([spacing_shape(coded), detector_shape(coded)])


def _labelled_shape(frames: Sequence[Frame]) -> dict[str, float]:
    """Group structure of the annotated frames: share alone, largest group, radius law."""
    alone = people = 0
    largest = 2
    sizes: dict[int, list[float]] = {}
    for frame in frames:
        if frame.groups is None:
            continue
        index = {int(i): k for k, i in enumerate(frame.ids)}
        people += frame.n_people
        together = 0
        for group in frame.fformations():
            rows = [index[m] for m in group]
            p = frame.position[rows]
            sizes.setdefault(len(rows), []).append(
                float(np.mean(np.hypot(*(p - p.mean(axis=0)).T)))
            )
            together += len(rows)
            largest = max(largest, len(rows))
        alone += frame.n_people - together
    if not sizes:
        return {}
    n = np.array([s for s, v in sizes.items() for _ in v], dtype=np.float64)
    r = np.array([x for v in sizes.values() for x in v])
    if len(set(n.tolist())) > 1:
        per, base = np.polyfit(n - 2.0, r, 1)
    else:
        per, base = 0.0, float(r.mean())
    return {
        "alone_share": alone / people if people else 0.0,
        "max_group_size": float(largest),
        "radius_base": float(base),
        "radius_per_member": float(per),
    }


def _clip(value: float, low: float, high: float) -> float:
    return float(min(high, max(low, value)))


def fit_twin(
    frames: Sequence[Frame],
    *,
    name: str,
    seed: int = 0,
    use_labels: bool = False,
    where: str | None = None,
    n_jobs: int = 1,
) -> Twin:
    """Fits a venue twin to ``frames`` (see the module docstring for the recipe).

    Args:
        frames: the recording's frames (a Dataset works too); their groups are removed first
            unless ``use_labels``.
        name: the recording's name, recorded in the twin.
        seed: master seed of the pilots and of the generated data.
        use_labels: also fit the group structure on the annotated frames.
        where: the file named by errors (default ``name``).
        n_jobs: processes the pilot parties of the crowd options' choices run on (the twin is
            the same, byte for byte, whatever the number).

    Raises:
        TwinInputError: a recording too small or in the wrong unit (`check_frames_for_twin`);
            with ``use_labels``, one without a group of two or more in its annotated frames.
    """
    where = where or name
    frames = list(frames)
    check_frames_for_twin(frames, where=where)
    shape = _labelled_shape(frames) if use_labels else {}
    if use_labels and not shape:  # no group to fit: a label-free twin would pass for one
        annotated = sum(frame.groups is not None for frame in frames)
        raise TwinInputError(
            f"{where}: field groups: expected annotated frames with a group of two or more to "
            "fit the group structure on (use_labels), found "
            + (f"none in its {annotated} annotated frames" if annotated else "no annotated frame")
        )
    if not use_labels:
        frames = _strip(frames)
    real = measure_place(frames)
    venue = venue_for(real.people_median)
    crowd = venue.scenario == CROWD
    standing = standing_share(frames) if crowd else math.nan

    people = int(_clip(round(real.people_median), *people_range(venue.scenario)))
    rate = _clip(real.rate_hz if math.isfinite(real.rate_hz) else 1.0, 0.05, 25.0)
    rate = 1.0 / (max(1, round(1.0 / rate / STEP_S)) * STEP_S)  # whole control steps a frame
    target = _clip(real.frames, MIN_TARGET_FRAMES, TARGET_FRAMES)
    duration = real.duration_s if math.isfinite(real.duration_s) else EPISODE_S[1]
    duration = _clip(min(duration, target / (MIN_EPISODES * rate)), *EPISODE_S)
    episodes = int(_clip(math.ceil(target / (duration * rate)), MIN_EPISODES, MAX_EPISODES))
    max_group = min(MAX_GROUP, people)
    options: dict[str, Any] = {
        "people": people,
        "max_group_size": max(2, max_group),
        venue.room: _room_for(venue, people, math.sqrt(people / 0.4)),
    }
    if crowd:  # everyone standing is in the corners (a queue is not told apart from them)
        options["queue_share"] = 0.0
        options["group_share"] = _group_share(standing, people)
    if shape:
        options["max_group_size"] = int(_clip(shape["max_group_size"], 2, min(12, people)))
        if not crowd:
            options["alone_share"] = _clip(shape["alone_share"], 0.0, 1.0)

    shape_fit = {}
    if not shape:
        options, shape_fit = _fit_spacing_shape(
            frames, real, options, seed=seed, n_jobs=n_jobs, venue=venue
        )

    scale = 1.0
    pilot: PlaceStatistics | None = None
    for round_ in range(PILOT_ROUNDS):
        if shape and not crowd:
            options["radius_base"] = _clip(shape["radius_base"] / scale, 0.3, 2.0)
            options["radius_per_member"] = _clip(shape["radius_per_member"] / scale, 0.0, 0.5)
        run = {**options, "duration": venue.pilot_s}
        sim_frames, run = _simulate(
            run, seed=derive_int(seed, PILOT, round_), rate=PILOT_RATE_HZ, venue=venue
        )
        options[venue.room] = run[venue.room]
        pilot = measure_place(sim_frames)
        scale = real.nn_median / pilot.nn_median
        if round_ < PILOT_ROUNDS - 1:  # the last round's room is the one the scale was fit on
            wanted = real.extent_m / scale  # the box holding everyone, in simulated metres
            side = options[venue.room] * wanted / pilot.extent_m
            options[venue.room] = _room_for(venue, people, side)
            if crowd:  # as many present and standing as in the recording: walkers go out and
                # come back, and some of the corners' people walk
                if pilot.people_median > 0:
                    present = people * real.people_median / pilot.people_median
                    people = int(_clip(round(present), *people_range(CROWD)))
                    options["people"] = people
                stood = standing_share(sim_frames)
                if math.isfinite(stood) and stood > 0:
                    wanted_share = options["group_share"] * standing / stood
                    options["group_share"] = _group_share(wanted_share, people)
    assert pilot is not None

    jitter = math.sqrt(max(0.0, real.position_jitter_m**2 - (scale * pilot.position_jitter_m) ** 2))
    turn = 0.0
    if real.directions == 0:
        turn = math.sqrt(max(0.0, real.yaw_jitter_rad**2 - pilot.yaw_jitter_rad**2))
    annotation = AnnotationModel(
        orientation="head" if real.yaw_is_head > 0.5 else "body",
        directions=real.directions or None,
        position_noise=float(f"{jitter:.4g}"),
        yaw_noise=float(f"{turn:.4g}"),
        dropout=float(f"{min(real.dropout, 0.5):.4g}"),
        scale=float(f"{scale:.6g}"),
    )
    options = {k: (float(f"{v:.6g}") if isinstance(v, float) else v) for k, v in options.items()}
    options["duration"] = float(f"{duration:.6g}")

    import scenarios

    options = scenarios.registry.check_options(venue.scenario, options)
    options = room_for_every_episode(
        options, seed=seed, episodes=episodes, scenario=venue.scenario
    )
    sample = _sample(options, annotation, seed=seed, rate=rate, venue=venue)
    mine = measure_place(sample)

    searched = tuple(
        Fitted(
            f"options.{key}", options[key], SHAPE_STATISTIC, shape_fit["real"], shape_fit["twin"]
        )  # fmt: skip
        for key in venue.choices
        if shape_fit
    )
    names = {row.name for row in searched}
    rows = _fitted(real, mine, options, annotation, rate, episodes, shape, venue)
    statistics = {"real": real.to_json(), "twin": mine.to_json()}
    if crowd:
        twin_standing = standing_share(sample)
        rows += _crowd_rows(real, options, standing, twin_standing)
        statistics["real"]["standing_share"] = _rounded(standing)
        statistics["twin"]["standing_share"] = _rounded(twin_standing)
    fitted = tuple(row for row in rows if row.name not in names) + searched
    return Twin(
        name=name,
        mode="labels" if use_labels else "label-free",
        scenario=venue.scenario,
        options=options,
        annotation=annotation,
        rate_hz=rate,
        episodes=episodes,
        seed=seed,
        fitted=fitted,
        statistics=statistics,
    )


def _group_share(share: float, people: int) -> float:
    """``share`` of the ``people`` standing in the concourse's corners, as it allows: none, or
    two a corner at least."""
    share = _clip(share if math.isfinite(share) else 0.0, 0.0, 1.0)
    return float(f"{share:.4g}") if round(share * people) >= 8 else 0.0


def _rounded(value: float) -> float | None:
    return float(f"{value:.6g}") if math.isfinite(value) else None


def _crowd_rows(
    real: PlaceStatistics, options: Mapping[str, Any], standing: float, twin_standing: float
) -> tuple[Fitted, ...]:
    """The rows a crowd's twin adds: why it is a concourse, who stands, and the queue."""
    most = people_range(SCENARIO)[1]
    return (
        Fitted(
            "scenario", CROWD, f"humans per frame, median: more than a {SCENARIO} party holds "
            f"({most})", real.people_median, float(options["people"]),
        ),
        Fitted(
            "options.group_share", options["group_share"], "share of people standing (slower "
            "than 0.3 m/s over a second), all of them in the corners",
            _rounded(standing), _rounded(twin_standing),
        ),
        Fitted(
            "options.queue_share", options["queue_share"], "not fitted: a queue is not told "
            "apart from people standing aside", None, None,
        ),
    )  # fmt: skip


def _fitted(
    real: PlaceStatistics,
    twin: PlaceStatistics,
    options: dict[str, Any],
    annotation: AnnotationModel,
    rate: float,
    episodes: int,
    shape: dict[str, float],
    venue: Venue,
) -> tuple[Fitted, ...]:
    r, t = real.to_json(), twin.to_json()

    def row(name: str, value: Any, statistic: str, key: str | None) -> Fitted:
        return Fitted(
            name, value, statistic, r.get(key) if key else None, t.get(key) if key else None
        )

    rows = [
        row("options.people", options["people"], "humans per frame, median", "people_median"),
        row("options.max_group_size", options["max_group_size"],
            "no more than the people (labels: the largest group)", None),
        row(f"options.{venue.room}", options[venue.room],
            "side of the box holding everyone, median (crowding)", "extent_m"),
        row("options.duration", options["duration"], "length of a sequence, median, seconds",
            "duration_s"),
        row("rate_hz", rate, "frames per second", "rate_hz"),
        row("episodes", episodes, f"about {TARGET_FRAMES} frames, at least {MIN_EPISODES} "
            "episodes", None),
        row("annotation.scale", annotation.scale, "nearest-neighbour distance, median",
            "nn_median"),
        row("annotation.directions", annotation.directions,
            "directions every yaw is coded in (0: continuous)", "directions"),
        row("annotation.orientation", annotation.orientation,
            "share of recorded yaws that are the head's", "yaw_is_head"),
        row("annotation.position_noise", annotation.position_noise,
            "position jitter of people standing still, per axis", "position_jitter_m"),
        row("annotation.yaw_noise", annotation.yaw_noise,
            "yaw jitter of people standing still", "yaw_jitter_rad"),
        row("annotation.dropout", annotation.dropout,
            "share of frames a person is missing between two that hold them", "dropout"),
        row("(check) density", None, "humans per square metre of that box, median",
            "density_per_m2"),
        row("(check) nn q10", None, "nearest-neighbour distance, 10% quantile", "nn_q10"),
        row("(check) arrivals", None, "people appearing per minute", "arrivals_per_min"),
    ]  # fmt: skip
    for key in ("alone_share", "radius_base", "radius_per_member"):
        if key in shape and key in options:
            rows.append(
                Fitted(
                    f"options.{key}",
                    options[key],
                    "labels: " + key.replace("_", " "),
                    float(f"{shape[key]:.6g}"),
                    None,
                )  # fmt: skip
            )
    return tuple(rows)

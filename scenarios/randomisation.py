"""``mingle-randomised``: parties whose every shape parameter is drawn from wide ranges.

Domain randomisation for training detectors that must work on data they have never seen: each
seed draws a party (`scenarios.mingle.MingleParams`) with the o-space radius law, the spread of
radii, place, facing and gaze noise, the largest group, how long people stay and stay alone, the
crowd's size and density and the passers-by, each uniformly within the ranges below. The
ranges cover both real datasets this project measures: SALSA's tight, noisy groups (radius law
0.444 + 0.067 (n - 2) m, facings noisy) and Babble's wide, regular circles (0.674 + 0.086
(n - 2) m, facings within 5 degrees of the centre), and go beyond them on both sides. The
closest spacing of people (SALSA's nearest-neighbour q10: 0.44 m) and how unevenly groups spread
round their centre (from Babble's even circles to beyond SALSA's Symmetry), the share of
side-by-side and presenter-audience groups and the furniture groups stand at are drawn too
(`docs/guide/crowds.md`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated

import numpy as np

from scenarios.mingle import MingleParams, build_mingle_in_room
from scenarios.registry import Range, SceneSeconds, register
from scenarios.scenario import Scenario, check_option

__all__ = ["RANGES", "draw_params", "mingle_randomised"]

# Uniform ranges of the drawn parameters (units as in MingleParams).
RANGES: dict[str, tuple[float, float]] = {
    "radius_base": (0.35, 0.85),  # metres (SALSA 0.44, Babble 0.67)
    "radius_per_member": (0.03, 0.12),  # metres (SALSA 0.067, Babble 0.086)
    "radius_spread": (0.0, 0.2),  # relative
    "position_noise": (0.0, 0.12),  # metres
    "orientation_noise": (0.0, 0.9),  # radians (Babble ~0.08, SALSA ~0.7)
    "head_noise": (0.0, 0.6),  # radians
    "max_group_size": (4, 8),  # members
    "mean_stay": (60.0, 600.0),  # seconds
    "mean_alone": (5.0, 40.0),  # seconds
    "alone_share": (0.0, 0.3),
    "density": (0.2, 0.8),  # people per m^2
    "passers_by": (0, 3),  # people
    "spacing": (0.43, 0.63),  # metres (shoulder to shoulder .. bodies as arm-enclosing discs)
    "unevenness": (0.0, 1.0),  # (even circles, as Babble .. beyond SALSA's uneven groups)
    "arrangements": (0.0, 0.4),  # share of side-by-side and presenter-audience groups
    "furniture": (0, 3),  # pieces: a table, a bar, a poster (corners: mingle only)
}
_INTEGERS = ("max_group_size", "passers_by", "furniture")


def draw_params(
    rng: np.random.Generator,
    *,
    people: int,
    duration: float,
    robot: bool,
) -> tuple[MingleParams, dict[str, float]]:
    """A party drawn from `RANGES` (one draw per range, in its order): its parameters and the
    values drawn."""
    drawn: dict[str, float] = {}
    for name, (low, high) in RANGES.items():
        if name in _INTEGERS:
            drawn[name] = int(rng.integers(int(low), int(high) + 1))
        else:
            drawn[name] = float(rng.uniform(low, high))
    density = drawn.pop("density")
    side = max(4.0, math.sqrt((people + drawn["passers_by"]) / density))
    drawn["room_side"] = side
    params = MingleParams(
        people=people,
        duration=duration,
        robot=robot,
        **drawn,  # type: ignore[arg-type]
    )
    drawn["density"] = density
    return params, drawn


@register("mingle-randomised", tags=("party", "randomised"), robot={"robot": True})
def mingle_randomised(
    *,
    seed: int,
    people_min: Annotated[int, Range(2, 100)] = 6,
    people_max: Annotated[int, Range(2, 100)] = 30,
    duration: SceneSeconds = 300.0,
    robot: bool = False,
) -> Scenario:
    """Domain-randomised mingling: group shape, noise, sizes and crowd density drawn per seed.

    Args:
        seed: seeds the drawn parameters and the party.
        people_min: fewest guests drawn.
        people_max: most guests drawn, at least people_min.
        duration: length of the party, seconds.
        robot: whether the robot stands by the west wall, watching.
    """
    name = "mingle-randomised"
    check_option(name, "people_max", people_max, low=people_min, high=100)
    rng = np.random.default_rng(seed)
    people = int(rng.integers(people_min, people_max + 1))
    params, drawn = draw_params(rng, people=people, duration=duration, robot=robot)
    party_seed = int(rng.integers(2**63 - 1))
    party = build_mingle_in_room(params, seed=party_seed, name=name)
    return dataclasses.replace(
        party,
        seed=seed,
        options={"drawn": {"people": people, **drawn}},  # its options are recorded before it
        description="mingling with every shape parameter drawn from wide ranges",
    )

"""Venue twins: from an unlabelled recording of a place, a simulated twin of that place.

A twin (`Twin`, frozen in ``twin.json``) is a scenario with its options and an annotation model
fitted to a recording's frames without their groups (`fit_twin`): spacing, people, crowding,
how orientations are coded, tracker jitter and dropouts, rate and scale. Its generated data tune
detectors for that place and predict how well they will do there (`sim.twins.tune`,
`sim.twins.predict`).
"""

from __future__ import annotations

from sim.twins.data import generate_twin, twin_data
from sim.twins.description import (
    TWIN_VERSION,
    Fitted,
    Twin,
    TwinFormatError,
    read_twin,
    twin_from_json,
    write_twin,
)
from sim.twins.fit import TwinInputError, check_frames_for_twin, fit_twin, twin_sample
from sim.twins.statistics import PlaceStatistics, measure_place

__all__ = [
    "TWIN_VERSION",
    "Fitted",
    "PlaceStatistics",
    "Twin",
    "TwinFormatError",
    "TwinInputError",
    "check_frames_for_twin",
    "fit_twin",
    "generate_twin",
    "measure_place",
    "read_twin",
    "twin_data",
    "twin_from_json",
    "twin_sample",
    "write_twin",
]

"""Calibration of the scripted scenarios against the real data: side-by-side numbers and checks.

`calibrate_scenarios` simulates every calibrated scenario with its default options over a few
seeds and measures it with the instrument used for the real data
(`reform.calibration.characterise_dataset` and `compare`):

* ``word-improv`` against Babble and ``mingle`` against SALSA (where the real data disagree,
  SALSA's groups being tighter, each follows its own): mean Tightness and Symmetry by group
  size, with the target that the mean Tightness lies within 0.1 m of the real value for every
  size the real data holds at least 5 times, and two-sample Kolmogorov-Smirnov statistics of
  Distance and Effort Angle for in-group and out-of-group pairs, each set against a bound taken
  from the real data themselves:

  - ``word-improv``: below the statistic between SALSA and Babble (the synthetic game must be
    closer to Babble than the other real dataset is);
  - ``mingle``: below the statistic between SALSA's two sessions (no further from SALSA than
    the same party recorded on another day);

* ``mingle-randomised``: the spread of Tightness by size its draws cover, beside both real
  datasets' means;
* the HRI scenes: their Tightness, Symmetry and pair features, for reference.

Every episode is an independent unit of work (`sim.executor`): they run on local processes or as
Ray tasks, and the report is the same whichever runs them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

import scenarios
from reform.calibration import (
    MIN_GROUPS,
    TIGHTNESS,
    TIGHTNESS_TOLERANCE_M,
    Characterisation,
    Comparison,
    characterise_dataset,
    compare,
)
from reform.frame import Dataset, Frame
from sim.episode import simulate_episode
from sim.executor import Executor

__all__ = [
    "CALIBRATED",
    "DEFAULT_SEEDS",
    "Calibration",
    "CalibrationReport",
    "calibrate_scenarios",
    "scenario_frames",
]

DEFAULT_SEEDS = 8  # episodes per scenario (seeds 0 .. n-1)
# scenario -> (reference dataset, frames per second). The rate only sets how many (strongly
# correlated) samples the means rest on: a frame a second of the game (Babble was annotated
# every 0.5 s), one every two seconds of the party (SALSA: every 3 s).
CALIBRATED: Mapping[str, tuple[str, float]] = {
    "word-improv": ("babble", 1.0),
    "mingle": ("salsa", 0.5),
}
RANDOMISED = "mingle-randomised"
RANDOMISED_RATE_HZ = 0.5  # Hz
HRI_SCENES = scenarios.PAPER_HRI_SCENES  # the paper's three scenes, a fixed set
HRI_RATE_HZ = 1.0  # Hz
COVERAGE_QUANTILES = (0.05, 0.5, 0.95)


def scenario_frames(
    name: str,
    *,
    seeds: int,
    rate: float,
    options: Mapping[str, Any] | None = None,
    executor: Executor | None = None,
) -> list[Frame]:
    """Ground-truth frames of ``seeds`` episodes (seeds 0 .. n-1) of scenario ``name`` at its
    natural length, the episodes run by ``executor`` (default: in this process)."""
    executor = Executor("local", jobs=1) if executor is None else executor
    units = [(name, seed, rate, options) for seed in range(seeds)]
    return [f for episode in executor.map(_episode_frames, units) for f in episode]


def _episode_frames(unit: tuple[str, int, float, Mapping[str, Any] | None]) -> tuple[Frame, ...]:
    """The ground-truth frames of one episode: ``(scenario, seed, rate, options)``."""
    name, seed, rate, options = unit
    return tuple(simulate_episode(name, seed=seed, rate=rate, options=options).dataset)


@dataclass(frozen=True, eq=False)
class Calibration:
    """One scenario against its reference.

    Attributes:
        comparison: Tightness and Symmetry by size and the KS statistics.
        bounds: ``(feature, kind) -> bound`` each KS statistic must stay below.
        bound_source: where the bounds come from (one line).
        seeds: episodes simulated.
        rate: frames per second.
    """

    comparison: Comparison
    bounds: Mapping[tuple[str, str], float]
    bound_source: str
    seeds: int
    rate: float

    @property
    def scenario(self) -> str:
        return self.comparison.candidate.name

    @property
    def reference(self) -> str:
        return self.comparison.reference.name

    def ks_failures(self) -> tuple[str, ...]:
        """KS statistics at or above their bound, one line each (empty: all below)."""
        out = []
        for k in self.comparison.ks:
            bound = self.bounds[(k.feature, k.kind)]
            if not k.statistic < bound:
                out.append(
                    f"{k.feature} {k.kind}: D = {k.statistic:.3f}, bound {bound:.3f} "
                    f"({self.bound_source})"
                )
        return tuple(out)

    def failures(self) -> tuple[str, ...]:
        """Every miss: Tightness sizes outside the tolerance, then KS statistics over bound."""
        return self.comparison.failures() + self.ks_failures()

    def to_json(self) -> dict[str, Any]:
        out = self.comparison.to_json()
        for entry in out["ks"]:
            entry["bound"] = self.bounds[(entry["feature"], entry["kind"])]
            entry["below_bound"] = entry["statistic"] < entry["bound"]
        out.update(
            seeds=self.seeds,
            rate_hz=self.rate,
            bound_source=self.bound_source,
            ks_failures=list(self.ks_failures()),
        )
        return out


@dataclass(frozen=True, eq=False)
class CalibrationReport:
    """Everything `calibrate_scenarios` measured.

    Attributes:
        calibrations: one per calibrated scenario.
        references: the real datasets' characterisations by name.
        randomised: the randomised mode's characterisation (or None when not run).
        hri: the HRI scenes' characterisations.
        seeds: episodes per scenario.
    """

    calibrations: tuple[Calibration, ...]
    references: Mapping[str, Characterisation]
    randomised: Characterisation | None = None
    hri: tuple[Characterisation, ...] = ()
    seeds: int = DEFAULT_SEEDS
    command: str = field(default="")

    def failures(self) -> tuple[str, ...]:
        return tuple(
            f"{c.scenario} vs {c.reference}: {line}"
            for c in self.calibrations
            for line in c.failures()
        )

    def coverage(self) -> list[dict[str, Any]]:
        """Tightness by size of the randomised mode (quantiles) beside each reference's mean."""
        if self.randomised is None:
            return []
        rows = []
        for size in self.randomised.sizes():
            values = self.randomised.samples(TIGHTNESS, size)
            if values.size < MIN_GROUPS:
                continue
            q = np.quantile(values, COVERAGE_QUANTILES)
            means = {
                name: _finite(ref.mean(TIGHTNESS, size)) for name, ref in self.references.items()
            }
            known = [m for m in means.values() if m is not None]
            rows.append(
                {
                    "size": size,
                    "groups": int(values.size),
                    "q05_m": float(q[0]),
                    "median_m": float(q[1]),
                    "q95_m": float(q[2]),
                    "reference_means_m": means,
                    "covers": bool(known) and all(q[0] <= m <= q[2] for m in known),
                }
            )
        return rows

    def to_json(self) -> dict[str, Any]:
        return {
            "command": self.command,
            "seeds": self.seeds,
            "tolerance_m": TIGHTNESS_TOLERANCE_M,
            "min_groups": MIN_GROUPS,
            "calibrations": [c.to_json() for c in self.calibrations],
            "references": {name: ref.to_json() for name, ref in self.references.items()},
            "randomised": None if self.randomised is None else self.randomised.to_json(),
            "randomised_coverage": self.coverage(),
            "hri": [h.to_json() for h in self.hri],
            "failures": list(self.failures()),
        }


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _bounds(comparison: Comparison) -> dict[tuple[str, str], float]:
    return {(k.feature, k.kind): k.statistic for k in comparison.ks}


def calibrate_scenarios(
    salsa: Dataset,
    babble: Dataset,
    *,
    seeds: int = DEFAULT_SEEDS,
    randomised: bool = True,
    hri: bool = True,
    command: str = "",
    executor: Executor | None = None,
) -> CalibrationReport:
    """Simulates the calibrated scenarios with default options and sets them beside SALSA and
    Babble (see the module doc).

    Args:
        salsa: SALSA, both sessions (``reform.datasets.load_salsa``).
        babble: Babble (``reform.datasets.load_babble``).
        seeds: episodes per scenario, seeds 0 .. n-1 (>= 1).
        randomised: also measure the randomised mode's coverage.
        hri: also measure the HRI scenes.
        command: the command line that made the report, for its header.
        executor: where the episodes run (`sim.executor.Executor`; default: in this process).
    """
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise ValueError(f"seeds must be an int >= 1, got {seeds!r}")
    refs = {
        "salsa": characterise_dataset(salsa, name="salsa"),
        "babble": characterise_dataset(babble, name="babble"),
    }
    for name, ref in refs.items():
        if ref.frames == 0:
            raise ValueError(f"{name}: the reference has no annotated frames")
    sessions = [
        characterise_dataset([f for f in salsa if f.sequence == s], name=f"salsa/{s}")
        for s in salsa.sequences()
    ]
    if len(sessions) != 2:
        raise ValueError(
            f"salsa: expected its two sessions, got sequences {list(salsa.sequences())}"
        )
    bounds = {
        "babble": (_bounds(compare(refs["salsa"], refs["babble"])), "SALSA against Babble"),
        "salsa": (
            _bounds(compare(sessions[0], sessions[1])),
            "SALSA session 1 against session 2",
        ),
    }
    # Every episode of every scenario, one unit each, in one map (the slowest scenario's
    # episodes do not wait for the others').
    rates = {name: rate for name, (_, rate) in CALIBRATED.items()}
    if randomised:
        rates[RANDOMISED] = RANDOMISED_RATE_HZ
    if hri:
        rates.update(dict.fromkeys(HRI_SCENES, HRI_RATE_HZ))
    units = [(name, seed, rate, None) for name, rate in rates.items() for seed in range(seeds)]
    executor = Executor("local", jobs=1) if executor is None else executor
    episodes = executor.map(_episode_frames, units, desc="calibrate", unit="episode")
    simulated: dict[str, list[Frame]] = {name: [] for name in rates}
    for (name, *_), frames_ in zip(units, episodes, strict=True):
        simulated[name].extend(frames_)

    calibrations = []
    for name, (reference, rate) in CALIBRATED.items():
        frames = simulated[name]
        measured = characterise_dataset(frames, name=name)
        limit, source = bounds[reference]
        calibrations.append(
            Calibration(
                comparison=compare(measured, refs[reference]),
                bounds=limit,
                bound_source=source,
                seeds=seeds,
                rate=rate,
            )
        )
    random_part = None
    if randomised:
        random_part = characterise_dataset(simulated[RANDOMISED], name=RANDOMISED)
    hri_parts = ()
    if hri:
        hri_parts = tuple(characterise_dataset(simulated[n], name=n) for n in HRI_SCENES)
    return CalibrationReport(
        calibrations=tuple(calibrations),
        references=refs,
        randomised=random_part,
        hri=hri_parts,
        seeds=seeds,
        command=command,
    )

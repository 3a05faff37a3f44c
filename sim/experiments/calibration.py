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
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from reform.calibration import (
    MIN_GROUPS,
    SYMMETRY,
    TIGHTNESS,
    TIGHTNESS_TOLERANCE_M,
    Characterisation,
    Comparison,
    characterise_dataset,
    compare,
)
from reform.frame import Dataset, Frame
from sim.episode import simulate_episode
from sim.experiments.tables import render_table

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
HRI_SCENES = ("hri-conversation", "hri-robot-excluded", "hri-passing")
HRI_RATE_HZ = 1.0  # Hz
COVERAGE_QUANTILES = (0.05, 0.5, 0.95)


def scenario_frames(
    name: str,
    *,
    seeds: int,
    rate: float,
    options: Mapping[str, Any] | None = None,
) -> list[Frame]:
    """Ground-truth frames of ``seeds`` episodes (seeds 0 .. n-1) of scenario ``name`` at its
    natural length."""
    frames: list[Frame] = []
    for seed in range(seeds):
        frames.extend(simulate_episode(name, seed=seed, rate=rate, options=options).dataset)
    return frames


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

    def to_markdown(self) -> str:
        return _markdown(self)


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
    calibrations = []
    for name, (reference, rate) in CALIBRATED.items():
        frames = scenario_frames(name, seeds=seeds, rate=rate)
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
        random_part = characterise_dataset(
            scenario_frames(RANDOMISED, seeds=seeds, rate=RANDOMISED_RATE_HZ), name=RANDOMISED
        )
    hri_parts = ()
    if hri:
        hri_parts = tuple(
            characterise_dataset(scenario_frames(n, seeds=seeds, rate=HRI_RATE_HZ), name=n)
            for n in HRI_SCENES
        )
    return CalibrationReport(
        calibrations=tuple(calibrations),
        references=refs,
        randomised=random_part,
        hri=hri_parts,
        seeds=seeds,
        command=command,
    )


# --------------------------------------------------------------------------------------------
# Report


def _n(value: float | None, digits: int, *, signed: bool = False) -> str:
    if value is None or not math.isfinite(value):
        return "-"
    return f"{value:+.{digits}f}" if signed else f"{value:.{digits}f}"


def _side_by_side(calibration: Calibration) -> str:
    comp = calibration.comparison
    cand, ref = comp.candidate, comp.reference
    rows = []
    for size in sorted(set(cand.sizes()) | set(ref.sizes())):
        checked = ref.count(size) >= MIN_GROUPS
        ct, rt = cand.mean(TIGHTNESS, size), ref.mean(TIGHTNESS, size)
        cs, rs = cand.mean(SYMMETRY, size), ref.mean(SYMMETRY, size)
        ok = "-"
        if checked:
            ok = (
                "yes"
                if cand.count(size) >= MIN_GROUPS and abs(ct - rt) <= TIGHTNESS_TOLERANCE_M
                else "no"
            )
        rows.append(
            [
                str(size),
                f"{cand.count(size):,}",
                f"{ref.count(size):,}",
                _n(ct, 3),
                _n(rt, 3),
                _n(ct - rt, 3, signed=True),
                ok,
                _n(cs, 1),
                _n(rs, 1),
            ]
        )
    headers = [
        "size",
        "groups (ours)",
        f"groups ({ref.name})",
        "Tightness ours (m)",
        f"{ref.name} (m)",
        "difference",
        "within 0.1 m",
        "Symmetry ours (deg)",
        f"{ref.name} (deg)",
    ]
    return render_table(headers, rows, style="markdown")


def _ks_table(calibration: Calibration) -> str:
    rows = []
    for k in calibration.comparison.ks:
        bound = calibration.bounds[(k.feature, k.kind)]
        rows.append(
            [
                f"{k.feature}",
                k.kind,
                _n(k.statistic, 3),
                _n(bound, 3),
                "yes" if k.statistic < bound else "no",
                f"{k.candidate_n:,}",
                f"{k.reference_n:,}",
                _n(k.candidate_median, 3),
                _n(k.reference_median, 3),
            ]
        )
    headers = ["feature", "pairs", "D", "bound", "below", "n", "ref. n", "median", "ref. median"]
    return render_table(headers, rows, style="markdown")


def _markdown(report: CalibrationReport) -> str:
    parts = ["# Calibration of the scenarios against SALSA and Babble", ""]
    if report.command:
        parts += ["Generated by:", "", "```", report.command, "```", ""]
    parts += [
        f"Each scenario runs with its default options, {report.seeds} episodes (seeds 0-"
        f"{report.seeds - 1}), ground truth by the scenario's rule (a group counts once its "
        "members stand at their places facing the centre). Tightness: mean distance of the "
        "members to the group's centre; Symmetry: sum over the gaps between adjacent members of "
        "|360/N - gap| (definitions.md). The real data are measured by this project "
        "(docs/results/characterisation.md): SALSA both sessions, Babble's annotated frames. "
        f"Target: mean Tightness within {TIGHTNESS_TOLERANCE_M:g} m of the real value for every "
        f"size the real data hold at least {MIN_GROUPS} times.",
        "",
        "Kolmogorov-Smirnov D: the largest gap between the empirical distribution functions of "
        "a pair feature (Distance in metres, Effort Angle in radians) over in-group or "
        "out-of-group pairs; 0 means identical samples. Each is set against a bound taken from "
        "the real data: for `word-improv`, D between SALSA and Babble (closer to Babble than the "
        "other real dataset is); for `mingle`, D between SALSA's two sessions (no further from "
        "SALSA than the same party on another day).",
        "",
    ]
    verdict = "all met" if not report.failures() else "missed: " + "; ".join(report.failures())
    parts += [f"**Verdict: {verdict}.**", ""]
    for cal in report.calibrations:
        comp = cal.comparison
        parts += [
            f"## {cal.scenario} against {cal.reference}",
            "",
            f"{comp.candidate.frames:,} annotated frames at {cal.rate:g} Hz, "
            f"{comp.candidate.fformations:,} F-formations; {cal.reference}: "
            f"{comp.reference.frames:,} frames, {comp.reference.fformations:,} F-formations.",
            "",
            _side_by_side(cal),
            "",
            f"Pair features (bound: {cal.bound_source}):",
            "",
            _ks_table(cal),
            "",
        ]
    coverage = report.coverage()
    if coverage:
        names = list(report.references)
        rows = [
            [
                str(c["size"]),
                f"{c['groups']:,}",
                _n(c["q05_m"], 3),
                _n(c["median_m"], 3),
                _n(c["q95_m"], 3),
                *[_n(c["reference_means_m"][n], 3) for n in names],
                "yes" if c["covers"] else "no",
            ]
            for c in coverage
        ]
        parts += [
            f"## {RANDOMISED}: the range it covers",
            "",
            "Tightness of every F-formation of the randomised parties, by size: the 5th, 50th "
            "and 95th percentiles beside the real datasets' means (covered: every real mean lies "
            "between the 5th and 95th percentiles).",
            "",
            render_table(
                [
                    "size",
                    "groups",
                    "q05 (m)",
                    "median (m)",
                    "q95 (m)",
                    *[f"{n} (m)" for n in names],
                    "covers",
                ],
                rows,
                style="markdown",
            ),
            "",
        ]
    parts += [
        "## Notes",
        "",
        "- The radius laws are fit to the real means (word-improv: least-squares line through "
        "Babble's Tightness by size; mingle: fit to SALSA's of the mean radius drawn, floored "
        "by body spacing; see the modules' docs). Simulated groups come out 0.01-0.02 m wider "
        "than planned: people walking into place stop 3 cm short of it.",
        "- SALSA's 5% closest in-group pairs stand under 0.51 m apart, closer than two bodies "
        "of this simulator can (0.63 m between places): mingle's in-group Distance "
        "distribution is narrower at the low end, its largest KS statistic.",
        "- Symmetry is reported, not targeted: SALSA's annotated groups are far less regular "
        "(58-158 degrees) than circles of people facing a shared centre, and the paper's "
        "Symmetry numbers could not be reproduced from either dataset "
        "(docs/results/characterisation.md).",
        "- Babble's out-of-group pairs are few (76; players who left were no longer tracked): "
        "its out-of-group statistics are weak evidence.",
        "- Rare sizes of the randomised mode come from few parties (few draws allow groups of "
        "8); the drawn radius laws themselves span both datasets for every size "
        "(tests/test_calibration_scenarios.py).",
        "",
    ]
    if report.hri:
        rows = []
        for part in report.hri:
            summary = part.pair_summary()
            if not part.sizes():
                rows.append(
                    [
                        part.name,
                        "-",
                        "0",
                        "-",
                        "-",
                        _n(summary["distance"]["out-of-group"]["median"], 3),
                    ]
                )
            for size in part.sizes():
                rows.append(
                    [
                        part.name,
                        str(size),
                        f"{part.count(size):,}",
                        _n(part.mean(TIGHTNESS, size), 3),
                        _n(part.mean(SYMMETRY, size), 1),
                        _n(summary["distance"]["out-of-group"]["median"], 3),
                    ]
                )
        parts += [
            "## The HRI scenes",
            "",
            "For reference (no real counterpart in the public data): F-formations by size, the "
            "robot counted as a member where it is one.",
            "",
            render_table(
                [
                    "scenario",
                    "size",
                    "groups",
                    "Tightness (m)",
                    "Symmetry (deg)",
                    "out-of-group median distance (m)",
                ],
                rows,
                style="markdown",
            ),
            "",
        ]
    return "\n".join(parts)

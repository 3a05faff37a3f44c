"""The GCFF comparison: GCFF as the REFORM paper set it, GCFF tuned on SALSA's training split,
and the reference code's own default, on the SALSA test split and on Babble, with one protocol.

Every detector is scored by :func:`reform.metrics.evaluate` on the same frames: the SALSA test
split of :func:`reform.time_split` (per session, the last ~40 % of annotated frames by time) and
every annotated Babble frame. GCFF is tuned on the SALSA training split only; nothing is fitted on
Babble. Evaluation results of other detectors (REFORM's classifiers) can be placed beside them.

Units of the paper's setting: the REFORM paper states "stride = 0.7, MDL = 30000". GCFF's
published settings are centimetres (stride 50-70, mdl 6,000-30,000), and 0.7 reads as metres, so
the setting is taken as stride 70 cm = 0.7 m and mdl 30,000 cm² = 3.0 m² (see reform.gcff).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from reform import __version__
from reform.detectors import make_detector, run_detector
from reform.frame import Dataset, Frame
from reform.gcff import (
    MDL_GRID_M2,
    MDL_M2,
    STRIDE_GRID_M,
    STRIDE_M,
    Gcff,
    GridSearch,
    gcff_labels,
    labels_to_partition,
)
from reform.metrics import PROTOCOL, evaluate
from reform.splits import time_split
from sim.experiments.paper import BABBLE, SALSA_TEST, split_json

__all__ = [
    "GCFF_ROWS",
    "PAPER_MDL_M2",
    "PAPER_SCORES",
    "PAPER_STRIDE_M",
    "SALSA_TEST",
    "BABBLE",
    "GcffComparison",
    "gcff_comparison",
]

PAPER_STRIDE_M = 0.7  # metres: the paper's "stride = 0.7"
PAPER_MDL_M2 = 3.0  # square metres: the paper's "MDL = 30000", read as cm²
SCHEMA_VERSION = 1  # of GcffComparison.to_json
GCFF_ROWS = 4  # rows of the comparison that run GCFF on every test frame (paper, reference
# default, tuned, units ignored): what the run costs beside its tuning

# The REFORM paper's own figures, T = 2/3, precision / recall / F1 in % (definitions.md).
PAPER_SCORES = {
    SALSA_TEST: {
        "GCFF": (63.8, 64.2, 64.2),
        "Weighted KNN": (78.1, 82.7, 80.3),
        "Bagged Trees": (78.3, 84.3, 81.2),
        "Logistic Regression": (71.3, 78.6, 74.8),
    },
    BABBLE: {
        "GCFF": (65.0, 75.0, 69.6),
        "Weighted KNN": (74.3, 87.5, 80.4),
        "Bagged Trees": (75.6, 90.0, 82.1),
        "Logistic Regression": (65.6, 80.0, 72.1),
    },
}


@dataclass(frozen=True)
class GcffComparison:
    """The comparison's results.

    Attributes:
        results: one ``Evaluation.to_json`` dict per (detector, dataset), GCFF rows first, then
            any added results; ``detector`` is the row's name, ``dataset`` one of
            :data:`SALSA_TEST`, :data:`BABBLE`.
        tuning: the grid search on the SALSA training split.
        frames: annotated frames per part: ``salsa-train``, ``salsa-test``, ``babble``.
        train_fraction: share of each SALSA session's annotated frames used for training.
        notes: free-text remarks printed under the tables.
        added: how many results came from elsewhere (:meth:`with_results`).
    """

    results: tuple[Mapping[str, Any], ...]
    tuning: GridSearch
    frames: Mapping[str, int]
    train_fraction: float
    notes: tuple[str, ...] = field(default=())
    added: int = 0

    def all_notes(self) -> tuple[str, ...]:
        """The notes, plus one saying so when no other detector's results were added."""
        if self.added:
            return self.notes
        return self.notes + (
            "REFORM's classifiers are not in this run. Score them on the same frames (SALSA "
            f"test split of reform.time_split, dataset '{SALSA_TEST}'; Babble, dataset "
            f"'{BABBLE}') and add their evaluation JSON with --with-results "
            "(reform-sim experiment gcff) or GcffComparison.with_results.",
        )

    def with_results(self, results: Sequence[Mapping[str, Any]]) -> GcffComparison:
        """A copy with more evaluation results (e.g. REFORM's), checked to be on the same frames.

        Each result needs ``detector``, ``dataset`` (:data:`SALSA_TEST` or :data:`BABBLE`) and
        ``frames`` equal to this comparison's count for that dataset. A result whose detector
        name (ignoring case) is already in the table for that dataset, e.g. another run of the
        majority baseline, is left out.
        """
        added = []
        present = {(str(r["detector"]).lower(), r["dataset"]) for r in self.results}
        for i, result in enumerate(results):
            dataset = result.get("dataset")
            if dataset not in (SALSA_TEST, BABBLE):
                raise ValueError(
                    f"results[{i}] dataset must be {SALSA_TEST!r} or {BABBLE!r}, got {dataset!r}"
                )
            if result.get("frames") != self.frames[dataset]:
                raise ValueError(
                    f"results[{i}] ({result.get('detector')!r} on {dataset}) must be scored on "
                    f"the same {self.frames[dataset]} frames, got {result.get('frames')}"
                )
            key = (str(result.get("detector")).lower(), dataset)
            if key not in present:
                present.add(key)
                added.append(result)
        return GcffComparison(
            results=self.results + tuple(added),
            tuning=self.tuning,
            frames=self.frames,
            train_fraction=self.train_fraction,
            notes=self.notes,
            added=self.added + len(added),
        )

    def summary(self) -> tuple[str, ...]:
        """One line per dataset: the two GCFF settings fixed before testing beside the added
        detectors.

        The settings are the paper's and the one tuned on the SALSA training split (the
        reference default and the units-ignored rows are context); the added detectors are the
        rows of :meth:`with_results` other than a majority baseline, given as a range. Empty
        when nothing was added.
        """
        lines = []
        for dataset, title in ((SALSA_TEST, "SALSA test split"), (BABBLE, "Babble")):
            rows = [r for r in self.results if r["dataset"] == dataset]
            others = [
                r
                for r in rows[len(rows) - self._added_on(dataset) :]
                if "majority" not in str(r["detector"]).lower()
            ]
            paper = [r for r in rows if str(r["detector"]).startswith("GCFF, paper (")]
            tuned = [r for r in rows if str(r["detector"]).startswith("GCFF, tuned")]
            if not others or not paper or not tuned:
                continue
            f1 = sorted(100 * r["2/3"]["f1"] for r in others)
            spread = f"{f1[0]:.1f}" if len(f1) == 1 else f"{f1[0]:.1f}-{f1[-1]:.1f}"
            lines.append(
                f"{title}: GCFF with the paper's setting {100 * paper[0]['2/3']['f1']:.1f}, "
                f"GCFF tuned on SALSA train {100 * tuned[0]['2/3']['f1']:.1f}; the added "
                f"detectors ({', '.join(str(r['detector']) for r in others)}) {spread}. "
                f"The paper's figures here: GCFF {PAPER_SCORES[dataset]['GCFF'][2]:.1f}, its "
                "classifiers "
                + "-".join(
                    f"{v:.1f}"
                    for v in (
                        min(f for k, (_, _, f) in PAPER_SCORES[dataset].items() if k != "GCFF"),
                        max(f for k, (_, _, f) in PAPER_SCORES[dataset].items() if k != "GCFF"),
                    )
                )
                + "."
            )
        return tuple(lines)

    def _added_on(self, dataset: str) -> int:
        """How many of the last results of ``dataset`` were added by :meth:`with_results`."""
        added = self.results[len(self.results) - self.added :] if self.added else ()
        return sum(1 for r in added if r["dataset"] == dataset)

    def to_json(self, *, command: str | None = None) -> dict[str, Any]:
        """A JSON-ready dict: the command, the split, the tuning and every evaluation."""
        search = self.tuning
        return {
            "schema_version": SCHEMA_VERSION,
            "kind": "reform-sim/gcff-comparison",
            "reform_version": __version__,
            "command": command,
            "protocol": PROTOCOL,
            "split": split_json(self.train_fraction, self.frames),
            "units": {
                "paper_setting": {
                    "as_stated": "stride = 0.7, MDL = 30000",
                    "read_as": "stride 70 cm = 0.7 m, mdl 30000 cm² = 3.0 m²",
                },
                "computation": "GCFF computes in centimetres; parameters given in m and m²",
            },
            "tuning": {
                "on": "salsa-train",
                "objective": f"F1 of the frame means at T = {search.threshold}",
                "best": {
                    "stride_m": search.best_stride,
                    "mdl_m2": search.best_mdl,
                    "f1": search.best_f1,
                },
                "grid": [
                    {"stride_m": float(s), "mdl_m2": float(m), "f1": float(f)}
                    for s, m, f in zip(search.stride, search.mdl, search.f1, strict=True)
                ],
            },
            "paper_scores_t_two_thirds_percent": {
                d: {k: list(v) for k, v in rows.items()} for d, rows in PAPER_SCORES.items()
            },
            "results": [dict(r) for r in self.results],
            "summary": list(self.summary()),
            "notes": list(self.all_notes()),
        }


class _UnitsIgnored:
    """GCFF fed metre positions with the paper's numbers as if they were centimetres.

    What "stride = 0.7, MDL = 30000" computes when the units are ignored: the length unit of
    the visibility penalty silently becomes the metre. Shown only to make the units question
    visible; it is not a setting anyone should use.
    """

    def __init__(self, *, stride: float, mdl: float) -> None:
        self.stride = stride
        self.mdl = mdl

    def get_params(self, deep: bool = False) -> dict[str, Any]:  # noqa: ARG002
        return {"stride": self.stride, "mdl": self.mdl, "units": "ignored (metre data as cm)"}

    def predict(self, frames: Sequence[Frame]) -> list[tuple[tuple[int, ...], ...]]:
        return [
            labels_to_partition(
                f.ids, gcff_labels(f.position, f.yaw, stride=self.stride, mdl=self.mdl, units="cm")
            )
            for f in frames
        ]


def _evaluate(
    name: str, detector: Any, frames: Sequence[Frame], dataset: str, source: str
) -> dict[str, Any]:
    """The detector's scores on ``frames``, its output checked (`reform.detectors.run_detector`)."""
    params = detector.get_params(deep=False) if hasattr(detector, "get_params") else {}
    params = {k: (list(v) if isinstance(v, tuple) else v) for k, v in params.items()}
    return evaluate(frames, run_detector(name, detector, frames)).to_json(
        detector=name, dataset=dataset, detector_params=params, source=source
    )


def gcff_comparison(
    salsa: Dataset,
    babble: Dataset,
    *,
    train_fraction: float = 0.6,
    stride_grid: Sequence[float] = STRIDE_GRID_M,
    mdl_grid: Sequence[float] = MDL_GRID_M2,
    orientation: str = "body",
) -> GcffComparison:
    """Runs the GCFF rows of the comparison.

    Rows: GCFF with the paper's setting (0.7 m, 3.0 m²), GCFF with the reference code's default
    (0.7 m, 1.0 m²), GCFF tuned on the SALSA training split, GCFF with the paper's numbers
    applied to metre data as if they were centimetres (the units question made visible), and the
    majority baseline, each on the SALSA test split and on Babble.

    Args:
        salsa: SALSA (both sessions), as :func:`reform.datasets.load_salsa` gives it.
        babble: Babble, as :func:`reform.datasets.load_babble` gives it.
        train_fraction: share of each SALSA session's annotated frames used for training.
        stride_grid: strides tried when tuning, metres.
        mdl_grid: mdl values tried when tuning, square metres.
        orientation: orientation GCFF uses, ``"body"`` (the paper's) or ``"head"``.

    Returns:
        The evaluations, the tuning and the frame counts.
    """
    train, test = time_split(salsa.annotated(), train_fraction=train_fraction)
    train, test = tuple(train), tuple(test)
    babble_frames = babble.annotated()
    if not train or not test or not babble_frames:
        raise ValueError(
            "the comparison needs annotated SALSA training and test frames and annotated Babble "
            f"frames, got {len(train)} / {len(test)} / {len(babble_frames)}"
        )
    tuned = Gcff(
        tune=True, stride_grid=stride_grid, mdl_grid=mdl_grid, orientation=orientation
    ).fit(train)
    detectors = [
        (
            "GCFF, paper (70 cm, 30000 cm²)",
            make_detector("gcff", stride=PAPER_STRIDE_M, mdl=PAPER_MDL_M2, orientation=orientation),
        ),
        (
            "GCFF, reference default (70 cm, 10000 cm²)",
            make_detector("gcff", stride=STRIDE_M, mdl=MDL_M2, orientation=orientation),
        ),
        (
            f"GCFF, tuned on SALSA train ({100 * tuned.stride_:g} cm, {1e4 * tuned.mdl_:g} cm²)",
            make_detector("gcff", stride=tuned.stride_, mdl=tuned.mdl_, orientation=orientation),
        ),
        (
            "GCFF, paper numbers with units ignored (0.7, 30000 on metres)",
            _UnitsIgnored(stride=PAPER_STRIDE_M, mdl=30000.0),
        ),
        ("Majority", make_detector("majority")),
    ]
    results = []
    for frames, dataset, source in (
        (test, SALSA_TEST, salsa.source),
        (babble_frames, BABBLE, babble.source),
    ):
        for name, detector in detectors:
            results.append(_evaluate(name, detector, frames, dataset, source))
    return GcffComparison(
        results=tuple(results),
        tuning=tuned.grid_search_,
        frames={"salsa-train": len(train), "salsa-test": len(test), "babble": len(babble_frames)},
        train_fraction=train_fraction,
    )

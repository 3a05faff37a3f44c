"""Venue twins against the real datasets: do they tune detectors and predict their F1?

For every real dataset, `run_twins`:

1. fits its **label-free twin** (`sim.twins.fit_twin`: the frames only, groups removed) and
   generates the twin's data (reused under ``root`` when there);
2. splits the real annotated frames in two halves by time (`reform.time_split` at 0.5 per
   sequence): every real score below is on the **second half**; the first half's labels are
   only used by the rows that say so (the label ceiling);
3. **tuning**: each tunable detector (`TUNED`: GCFF's stride x mdl, the proximity baseline's
   distance; REFORM trained) with one setting for every dataset (its declared defaults; REFORM:
   trained on SALSA's first half, or Babble's for SALSA), tuned on the twin, and the same search
   run on the first half's labels (the ceiling);
4. **prediction**: every catalogued detector a twin can run (`sim.twins.predict`), its F1 on the
   twin calibrated by the detectors' agreement on the second half's frames (groups removed:
   predicted) against its F1 on the real second half, and beside it the twin's F1 alone; and the
   **real ceiling**, its F1 on the first half against the second. Over all (detector, dataset)
   cells: Pearson r, Spearman's rho, Kendall's tau, the mean absolute error (points) and the
   mean maximum rank violation (SIMPLER's MMRV: per dataset, for each detector the largest real
   gap to a detector the prediction orders the other way, averaged, then averaged over
   datasets), each with a 95 % bootstrap interval (detectors resampled, the same in every
   dataset); and the **noise floor** of the last two (`noise_floor`): what a predictor that knew
   each cell's expected real F1 would score against the second halves, from each real F1's own
   block-bootstrap spread;
5. **leave one out**: the twin recipe (`sim.twins.fit`) has no constant chosen on the real
   datasets' labels (each twin reads only its own frames), so its figures are already those of a
   recipe fixed without the dataset; beside them, one recipe constant that labels could fix, a
   line from twin F1 to real F1, is fitted on the other datasets' cells and applied to each
   held-out dataset (``loo_calibrated``).

The report (`sim.experiments.twins_report`) imports this module's result; this module never
imports its report.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from reform.frame import Dataset, Frame
from reform.seeding import derive_rng

__all__ = [
    "GOALS",
    "TUNED",
    "TwinsResult",
    "across_seeds",
    "agreement",
    "goal_figures",
    "mmrv",
    "noise_floor",
    "place_errors",
    "run_twins",
]

TUNED = ("gcff", "proximity", "reform")  # detectors tuned three ways (grids of the catalogue)
HALF = 0.5  # share of each sequence's annotated frames in the first half
RESAMPLES = 2000  # bootstrap resamples of the agreement figures
BOOTSTRAP = 31  # seed role of those draws
SPREAD_RESAMPLES = 500  # block-bootstrap resamples of each real F1 (its sampling spread)
SPREAD = 32  # seed role of those
FLOOR_DRAWS = 2000  # draws of the real scores about their expected values (the noise floor)
FLOOR = 33  # seed role of those
GOALS = {  # issue 28's figures (F1 points at T = 2/3)
    "tuning_gain": 5.0,  # GCFF twin-tuned at least this above one setting (mean)
    "tuning_gap": 2.0,  # ... and within this of the label-tuned search
    "pearson": 0.85,
    "mae": 5.0,
    "mmrv": 3.0,
}


@dataclass(frozen=True)
class TwinsResult:
    """What `run_twins` measured (F1 as fractions in [0, 1]).

    Attributes:
        datasets: names, in order.
        twins: dataset -> its twin (``Twin.to_json()``).
        frames: dataset -> (annotated frames of the first half, of the second half).
        tuning: rows ``{"dataset", "detector", "how", "options", "f1"}`` (``how``: ``one
            setting``, ``twin``, ``labels``).
        cells: rows ``{"dataset", "detector", "predicted", "low", "high", "twin_alone",
            "real", "real_sd", "first_half"}`` (``twin_alone``: the F1 on the twin before the
            calibration at the place; ``real_sd``: the real F1's sampling spread,
            `_real_score`), and where the prediction was calibrated ``"agreement_twin"`` and
            ``"agreement_place"`` (the detector's F1 against the consensus on each).
        agreement: ``{"twin": {...}, "twin_alone": {...}, "ceiling": {...}, ...}``: each
            measure's value and interval.
        noise_floor: the MAE and MMRV (points) a predictor that knew every cell's expected
            real F1 would score against the real scores, from their own sampling spread
            (`noise_floor`): ``{"mae": {...}, "mmrv": {...}}``, each value and interval.
        seconds: wall-clock time of the run.
        seed: the master seed of the twins and their data.
        seeds: the goals' figures over runs with other master seeds (`across_seeds`), empty
            for one run.
    """

    datasets: tuple[str, ...]
    twins: Mapping[str, Any]
    frames: Mapping[str, tuple[int, int]]
    tuning: tuple[Mapping[str, Any], ...]
    cells: tuple[Mapping[str, Any], ...]
    agreement: Mapping[str, Any]
    own_settings: Mapping[str, float] = field(default_factory=dict)
    noise_floor: Mapping[str, Any] = field(default_factory=dict)
    seconds: float = 0.0
    seed: int = 0
    seeds: Mapping[str, Any] = field(default_factory=dict)

    def to_json(self, *, command: str = "") -> dict[str, Any]:
        return {
            "command": command,
            "datasets": list(self.datasets),
            "mode": "label-free",
            "twins": dict(self.twins),
            "frames": {k: list(v) for k, v in self.frames.items()},
            "tuning": [dict(r) for r in self.tuning],
            "cells": [dict(c) for c in self.cells],
            "agreement": dict(self.agreement),
            "own_settings": dict(self.own_settings),
            "noise_floor": dict(self.noise_floor),
            "leave_one_out": "each twin reads its own frames only; one constant of the recipe "
            "was chosen on these datasets' labels: tune's lean, GCFF's cheapest group within "
            "2 points of the best F1 on the twin (sim.twins.tune.TIE_F1), chosen on seeds 0-5's "
            "twins of these four datasets (GCFF's grid scored on each twin and on each second "
            "half): 1.6 points short of the label search at 2 points; chosen among 1, 2, 3 and 5 "
            "points on the other three datasets, each held out: 1.7 short; loo_calibrated: each "
            "cell through the line from twin F1 to real F1 fitted on the other datasets' cells",
            "goals": GOALS,
            "seed": self.seed,
            "seeds": dict(self.seeds),
            "seconds": self.seconds,
        }


def goal_figures(result: TwinsResult) -> dict[str, float]:
    """The goals' figures of one run (`GOALS`): GCFF tuned on the twin against one setting
    (``tuning_gain``) and against the label search (``tuning_gap``: labels minus twin), mean
    F1 points over the datasets; the twin's prediction over all cells: Pearson r, MAE and MMRV
    (points)."""
    gcff: dict[str, list[float]] = {}
    for row in result.tuning:
        if row["detector"] == "gcff":
            gcff.setdefault(row["how"], []).append(100.0 * row["f1"])
    mean = {how: float(np.mean(v)) for how, v in gcff.items()}
    nan = math.nan
    twin = result.agreement["twin"]
    return {
        "tuning_gain": mean.get("twin", nan) - mean.get("one setting", nan),
        "tuning_gap": mean.get("labels", nan) - mean.get("twin", nan),
        "pearson": float(twin["pearson"]["value"]),
        "mae": float(twin["mae"]["value"]),
        "mmrv": float(twin["mmrv"]["value"]),
    }


def _mean_cells(runs: Sequence[Sequence[Mapping[str, Any]]]) -> list[dict[str, Any]]:
    """The first run's cells, each with its predicted and its real F1 averaged over the
    ``runs``' cells (the cells every run predicted). A catalogued detector's real F1 is the same
    in every run; a detector trained or tuned on each run's twin (REFORM trained on it, GCFF
    tuned on it) is another model in each, and the mean prediction is compared with the mean of
    their real F1s."""
    by: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for cells in runs:
        for c in cells:
            by.setdefault((c["dataset"], c["detector"]), []).append(c)
    out = []
    for c in runs[0]:
        same = by[c["dataset"], c["detector"]]
        if len(same) == len(runs):
            mean = {k: float(np.mean([one[k] for one in same])) for k in ("predicted", "real")}
            out.append(dict(c, **mean))
    return out


def _ensemble_cells(
    runs: Sequence[Sequence[Mapping[str, Any]]], per_place: int
) -> list[list[dict[str, Any]]]:
    """Each ensemble's cells (`_mean_cells` of ``per_place`` consecutive runs), in order."""
    return [_mean_cells(runs[k : k + per_place]) for k in range(0, len(runs), per_place)]


def _spread(figures: Sequence[Mapping[str, float]]) -> dict[str, dict[str, float]]:
    return {
        key: {
            "mean": float(np.mean([f[key] for f in figures])),
            "low": float(np.min([f[key] for f in figures])),
            "high": float(np.max([f[key] for f in figures])),
        }
        for key in figures[0]
    }


def across_seeds(results: Sequence[TwinsResult], *, per_place: int = 1) -> dict[str, Any]:
    """The goals' figures of runs that differ only in their master seed (each twin fitted, its
    data generated and its detectors scored again): each run's (`goal_figures`), and those of
    the **seeds' mean prediction** (each cell's predicted F1 averaged over the runs, against the
    same real F1).

    With ``per_place`` above 1, a place is predicted by that many twins (consecutive runs, as
    ``benchmark --twin A --twin B ...`` predicts: the mean of their predictions) and the goals
    are judged per such **ensemble**: the tuning figures are its twins' mean, the prediction's
    those of its mean prediction. ``spread`` is the mean, lowest and highest over the ensembles
    (over the single runs when ``per_place`` is 1; ``single`` keeps theirs); ``cells`` keeps
    every run's cells (seed -> the cells' detectors, predicted, twin-alone and real F1).

    Raises:
        ValueError: a number of runs that is not a multiple of ``per_place``.
    """
    if per_place < 1 or len(results) % per_place:
        raise ValueError(
            f"per_place: expected a divisor of the {len(results)} runs, found {per_place}"
        )
    per_seed = [goal_figures(r) for r in results]
    ensembles = []
    if per_place > 1:
        runs = [r.cells for r in results]
        for k, cells in enumerate(_ensemble_cells(runs, per_place)):
            block = slice(k * per_place, (k + 1) * per_place)
            measures = agreement(cells, "predicted", seed=results[block][0].seed)
            ensembles.append(
                {
                    "seeds": [r.seed for r in results[block]],
                    **{
                        key: float(np.mean([f[key] for f in per_seed[block]]))
                        for key in ("tuning_gain", "tuning_gap")
                    },
                    **{key: measures[key]["value"] for key in ("pearson", "mae", "mmrv")},
                }
            )
    figures_of = [{k: v for k, v in e.items() if k != "seeds"} for e in ensembles]
    mean_prediction = agreement(
        _mean_cells([r.cells for r in results]), "predicted", seed=results[0].seed
    )
    return {
        "seeds": [r.seed for r in results],
        "per_place": per_place,
        "per_seed": per_seed,
        "single": _spread(per_seed),
        "ensembles": ensembles,
        "spread": _spread(figures_of if per_place > 1 else per_seed),
        "mean_prediction": {k: v["value"] for k, v in mean_prediction.items()},
        "cells": {str(r.seed): [_brief(c) for c in r.cells] for r in results},
    }


def place_errors(seeds: Mapping[str, Any]) -> dict[str, dict[str, list[float]]]:
    """Each dataset's MAE and MMRV (points) of each ensemble's mean prediction, from the cells
    `across_seeds` keeps for every run: dataset -> ``{"mae": [...], "mmrv": [...]}``, one value
    per ensemble, in their order (empty without kept cells)."""
    kept = seeds.get("cells") or {}
    per_place = int(seeds.get("per_place", 1))
    runs = [kept[str(seed)] for seed in seeds.get("seeds", ()) if str(seed) in kept]
    if not runs or len(runs) != len(seeds["seeds"]):
        return {}
    out: dict[str, dict[str, list[float]]] = {}
    for ensemble in _ensemble_cells(runs, per_place):
        by_dataset: dict[str, list[dict[str, Any]]] = {}
        for cell in ensemble:
            by_dataset.setdefault(cell["dataset"], []).append(cell)
        for name, cells in by_dataset.items():
            figures = _measures(cells, "predicted")
            entry = out.setdefault(name, {"mae": [], "mmrv": []})
            entry["mae"].append(figures["mae"])
            entry["mmrv"].append(figures["mmrv"])
    return out


def _brief(cell: Mapping[str, Any]) -> dict[str, Any]:
    """A cell as `across_seeds` keeps it for every run: what a re-analysis needs."""
    keys = ("dataset", "detector", "predicted", "twin_alone", "real", "agreement_twin",
            "agreement_place")  # fmt: skip
    return {k: cell[k] for k in keys if k in cell}


def _f1(name: str, detector: Any, frames: Sequence[Frame]) -> float:
    from sim.twins.tune import detector_f1

    return detector_f1(name, detector, frames)


def mmrv(predicted: Sequence[float], real: Sequence[float]) -> float:
    """Mean maximum rank violation (SIMPLER): for each detector the largest real gap to one the
    prediction orders the other way (0 when none), averaged over the detectors."""
    p, r = np.asarray(predicted, dtype=float), np.asarray(real, dtype=float)
    if p.size < 2:
        return 0.0
    disagree = np.sign(p[:, None] - p[None, :]) != np.sign(r[:, None] - r[None, :])
    gaps = np.where(disagree, np.abs(r[:, None] - r[None, :]), 0.0)
    return float(gaps.max(axis=1).mean())


def _real_score(
    name: str, detector: Any, frames: Sequence[Frame], weights: np.ndarray
) -> tuple[float, float]:
    """F1 at T = 2/3 of ``detector`` on the annotated ``frames`` (as `_f1`), and its sampling
    spread: the standard deviation of that F1 over the block-bootstrap ``weights`` (resamples x
    frames; contiguous stretches of each recording resampled whole)."""
    from reform.detectors import run_detector
    from reform.metrics import evaluate
    from sim.twins.tune import THRESHOLD

    frames = [f for f in frames if f.groups is not None]
    scores = evaluate(frames, run_detector(name, detector, frames), thresholds=(THRESHOLD,))
    scores = scores.at(THRESHOLD)
    total = weights.sum(axis=1)
    p = weights @ np.asarray(scores.frame_precision, dtype=float) / total
    r = weights @ np.asarray(scores.frame_recall, dtype=float) / total
    both = p + r
    f1 = np.where(both > 0, 2.0 * p * r / np.where(both > 0, both, 1.0), 0.0)
    return float(scores.f1), float(np.std(f1))


def noise_floor(
    cells: Sequence[Mapping[str, Any]], *, seed: int = 0, draws: int = FLOOR_DRAWS
) -> dict[str, dict[str, float]]:
    """What the real scores' own sampling error costs any prediction: the MAE and MMRV
    (points) of a predictor that knew every cell's expected real F1 exactly, against real
    scores drawn about it with each cell's spread (``real_sd``, `_real_score`; normal, clipped
    to [0, 1]); each ``{"value", "low", "high"}``: the mean over ``draws`` and its 95 % range.
    The twin's figures cannot be expected below these."""
    rng = derive_rng(seed, FLOOR)
    by_dataset: dict[str, list[Mapping[str, Any]]] = {}
    for c in cells:
        by_dataset.setdefault(c["dataset"], []).append(c)
    errors, violations = [], []
    for _ in range(draws):
        apart, ranks = [], []
        for group in by_dataset.values():
            expected = np.array([c["real"] for c in group], dtype=float)
            spread = np.array([c["real_sd"] for c in group], dtype=float)
            drawn = np.clip(expected + rng.normal(0.0, 1.0, expected.size) * spread, 0.0, 1.0)
            apart.append(np.abs(drawn - expected))
            ranks.append(mmrv(expected, drawn))
        errors.append(100.0 * float(np.mean(np.concatenate(apart))))
        violations.append(100.0 * float(np.mean(ranks)))
    out = {}
    for name, values in (("mae", errors), ("mmrv", violations)):
        low, high = np.quantile(values, [0.025, 0.975])
        out[name] = {"value": float(np.mean(values)), "low": float(low), "high": float(high)}
    return out


def _measures(cells: Sequence[Mapping[str, Any]], key: str) -> dict[str, float]:
    from scipy import stats

    p = np.array([c[key] for c in cells], dtype=float)
    r = np.array([c["real"] for c in cells], dtype=float)
    out = {"pearson": math.nan, "spearman": math.nan, "kendall": math.nan}
    if p.size > 2 and np.ptp(p) > 0 and np.ptp(r) > 0:
        out["pearson"] = float(stats.pearsonr(p, r)[0])
        out["spearman"] = float(stats.spearmanr(p, r)[0])
        out["kendall"] = float(stats.kendalltau(p, r)[0])
    out["mae"] = float(np.mean(np.abs(p - r))) * 100.0
    by_dataset: dict[str, list[Mapping[str, Any]]] = {}
    for c in cells:
        by_dataset.setdefault(c["dataset"], []).append(c)
    out["mmrv"] = 100.0 * float(
        np.mean([mmrv([c[key] for c in cs], [c["real"] for c in cs]) for cs in by_dataset.values()])
    )
    return out


def agreement(
    cells: Sequence[Mapping[str, Any]], key: str, *, seed: int = 0, resamples: int = RESAMPLES
) -> dict[str, dict[str, float]]:
    """Pearson r, Spearman, Kendall, MAE and MMRV (points) of ``key`` against ``real`` over
    ``cells``, each ``{"value", "low", "high"}`` (95 % bootstrap: detectors resampled with
    replacement, the same detectors in every dataset)."""
    point = _measures(cells, key)
    detectors = sorted({c["detector"] for c in cells})
    rng = derive_rng(seed, BOOTSTRAP)
    samples: dict[str, list[float]] = {k: [] for k in point}
    by_detector: dict[str, list[Mapping[str, Any]]] = {}
    for c in cells:
        by_detector.setdefault(c["detector"], []).append(c)
    for _ in range(resamples):
        picks = rng.integers(len(detectors), size=len(detectors))
        drawn = []
        for k, d in enumerate(picks):
            drawn += [dict(c, detector=f"{c['detector']}#{k}") for c in by_detector[detectors[d]]]
        for name, value in _measures(drawn, key).items():
            samples[name].append(value)
    out = {}
    for name, value in point.items():
        finite = np.array([v for v in samples[name] if math.isfinite(v)])
        low, high = np.quantile(finite, [0.025, 0.975]) if finite.size else (math.nan, math.nan)
        out[name] = {"value": value, "low": float(low), "high": float(high)}
    return out


def _loo_calibrated(cells: Sequence[Mapping[str, Any]]) -> list[float]:
    """Each cell's prediction through the recipe's one constant fixed on the other datasets:
    the least-squares line from twin F1 to real F1 over their cells (one line per held-out
    dataset), clipped to [0, 1]; the prediction itself where the other datasets' predictions
    do not differ (no line to draw)."""
    from sim.twins.predict import line_through

    lines = {}
    for name in {c["dataset"] for c in cells}:
        others = [c for c in cells if c["dataset"] != name]
        lines[name] = line_through([c["predicted"] for c in others], [c["real"] for c in others])
    out = []
    for c in cells:
        line = lines[c["dataset"]]
        if line is None:
            out.append(float(c["predicted"]))
            continue
        slope, intercept = line
        out.append(float(np.clip(intercept + slope * c["predicted"], 0.0, 1.0)))
    return out


def _reference_model(name: str, real: Mapping[str, Dataset]) -> Any:
    """REFORM with one setting for all, as the paper trains it: on SALSA's first half (the
    first dataset's when there is no SALSA); never on a second half."""
    from reform.classifiers import make_classifier
    from reform.detector import Reform
    from reform.splits import time_split

    source = "salsa" if "salsa" in real else next(iter(real))
    first, _ = time_split(real[source].annotated(), HALF)
    return Reform(make_classifier("bagged-trees")).fit(first), source


def _own_settings(dataset: Dataset) -> Any:
    """GCFF with the settings the dataset ships, or None."""
    from reform.detectors import DetectorError, detector_names, make_detector, prepare_detector

    if "gcff-own" not in detector_names():
        return None
    try:
        return prepare_detector("gcff-own", make_detector("gcff-own"), dataset=dataset)
    except (DetectorError, ValueError):
        return None


def run_twins(
    real: Mapping[str, Dataset],
    *,
    root: str | Path,
    seed: int = 0,
    detectors: Sequence[str] | None = None,
    tuned: Sequence[str] = TUNED,
    episodes: int | None = None,
    jobs: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> TwinsResult:
    """The experiment (module docstring) on the datasets ``real`` (name -> dataset).

    Args:
        real: the real datasets.
        root: folder of the twins and their generated data (``root/NAME/``), reused.
        seed: master seed of the twins and their data.
        detectors: catalogue names predicted (default: every one a twin can run).
        tuned: the detectors tuned three ways (default `TUNED`; GCFF's twin-tuned setting is
            also predicted when ``gcff`` is among them).
        episodes: at most this many episodes of each twin's data (a smoke run); None: the
            twin's own.
        jobs: processes fitting the twins (their pilot parties), generating their data and
            searching the detectors' grids (None: every core).
        progress: called with a line at each step.
    """
    from reform.bootstrap import bootstrap_weights
    from reform.detectors import make_detector
    from reform.splits import time_split
    from sim.executor import cpu_count
    from sim.experiments.benchmark import bootstrap_blocks
    from sim.twins import fit_twin, twin_data, write_twin
    from sim.twins.predict import catalogue_candidates, predict
    from sim.twins.tune import search_grid, tune_detector, tuning_frames

    started = time.perf_counter()
    workers = jobs or cpu_count()  # fitting the twins and searching the detectors' grids
    say = progress or (lambda _: None)
    root = Path(root)
    twins, frames_of, tuning, cells, own = {}, {}, [], [], {}
    for name, dataset in real.items():
        say(f"{name}: fitting its twin on {len(dataset)} frames, labels removed")
        twin = fit_twin(list(dataset), name=name, seed=seed, n_jobs=workers)
        (root / name).mkdir(parents=True, exist_ok=True)
        write_twin(twin, root / name / "twin.json")
        twins[name] = twin.to_json()
        if episodes is not None:
            twin = dataclasses.replace(twin, episodes=min(twin.episodes, episodes))
        data = list(twin_data(twin, root / name / "twin-data", n_jobs=jobs))
        first, second = time_split(dataset.annotated(), HALF)
        frames_of[name] = (len(first), len(second))
        spread = bootstrap_weights(
            bootstrap_blocks(second),
            rng=derive_rng(seed, SPREAD, len(frames_of)),
            resamples=SPREAD_RESAMPLES,
        )

        say(f"{name}: tuning {', '.join(tuned)} on the twin and on the first half's labels")
        twin_options = {}
        for detector in tuned:
            if detector == "reform":
                reference, source = _reference_model(name, real)
                on_twin = tune_detector("reform", data)
                on_labels = tune_detector("reform", first)
                rows = [
                    ("one setting", {"trained on": f"{source}, first half"}, reference),
                    ("twin", {"trained on": "twin"}, on_twin.model),
                    ("labels", {"trained on": "first half"}, on_labels.model),
                ]
            else:
                chosen = tune_detector(detector, data, n_jobs=workers).options
                labelled = search_grid(
                    detector, tuning_frames(first, 10**9), n_jobs=workers
                ).options
                twin_options[detector] = chosen
                rows = [
                    ("one setting", {}, make_detector(detector)),
                    ("twin", dict(chosen), make_detector(detector, **chosen)),
                    ("labels", dict(labelled), make_detector(detector, **labelled)),
                ]
            for how, options, model in rows:
                tuning.append(
                    {
                        "dataset": name,
                        "detector": detector,
                        "how": how,
                        "options": options,
                        "f1": _f1(detector, model, second),
                    }
                )
        shipped = _own_settings(dataset)
        if shipped is not None:
            own[name] = _f1("gcff-own", shipped, second)

        extra = {"gcff (twin-tuned)": twin_options["gcff"]} if "gcff" in twin_options else {}
        candidates = catalogue_candidates(tuned=extra)
        if detectors is not None:
            candidates = [c for c in candidates if c.name in detectors or c.label in detectors]
        say(f"{name}: predicting {len(candidates)} detectors on the twin")
        # The second half's frames calibrate the predictions by the detectors' agreement there:
        # `predict` removes their groups before it runs anything on them.
        for p in predict(
            data,
            candidates,
            place=second,
            seed=seed,
            progress=lambda label, name=name: say(f"{name}: {label}"),
        ):
            if p.f1 is None:
                continue
            label = p.label
            name_of = next(c.name for c in candidates if c.label == label)
            score, score_sd = _real_score(name_of, p.detector, second, spread)
            cells.append(
                {
                    "dataset": name,
                    "detector": label,
                    "predicted": p.f1,
                    "low": p.low,
                    "high": p.high,
                    "twin_alone": p.on_twin,
                    "real": score,
                    "real_sd": score_sd,
                    "first_half": _f1(name_of, p.detector, first),
                }
            )
            if p.agreement is not None:
                cells[-1]["agreement_twin"], cells[-1]["agreement_place"] = p.agreement
    for cell, loo in zip(cells, _loo_calibrated(cells), strict=True):
        cell["loo_calibrated"] = loo
    result_agreement = {
        "twin": agreement(cells, "predicted", seed=seed),
        "twin_alone": agreement(cells, "twin_alone", seed=seed),
        "ceiling": agreement(cells, "first_half", seed=seed),
        "twin_loo_calibrated": agreement(cells, "loo_calibrated", seed=seed),
        "twin_without_majority": agreement(
            [c for c in cells if c["detector"] != "majority"], "predicted", seed=seed
        ),
    }
    return TwinsResult(
        datasets=tuple(real),
        twins=twins,
        frames=frames_of,
        tuning=tuple(tuning),
        cells=tuple(cells),
        agreement=result_agreement,
        own_settings=own,
        noise_floor=noise_floor(cells, seed=seed),
        seconds=time.perf_counter() - started,
        seed=seed,
    )

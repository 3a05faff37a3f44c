"""The benchmark's report: a Markdown table as the field reports it, JSON, a plot, recordings.

Imports the run (:mod:`sim.experiments.benchmark`); the run never imports its report.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from reform.atomic import atomic_path
from sim.experiments.benchmark import (
    ORIGINAL_GCFF_OWN,
    THRESHOLDS,
    Benchmark,
    Cell,
    percent,
)
from sim.experiments.report_files import write_json, write_markdown

__all__ = [
    "JSON_NAME",
    "MARKDOWN_NAME",
    "PLOT_NAME",
    "RECORDINGS",
    "plot",
    "record",
    "to_json",
    "to_markdown",
    "write_report",
]

MARKDOWN_NAME = "benchmark.md"
JSON_NAME = "benchmark.json"
PLOT_NAME = "benchmark.png"
RECORDINGS = "recordings"  # the folder of the per-dataset .rrd files
PLOT_DPI = 120
JSON_SCHEMA_VERSION = 1


def _row(values: tuple[float, float, float] | None) -> list[str]:
    return [percent(v) for v in values] if values else ["–", "–", "–"]


def _interval_text(interval: tuple[float, float] | None) -> str:
    """``"80.1–88.0"``: a bootstrap interval of an F1, in %."""
    if interval is None:
        return "–"
    return f"{percent(interval[0])}–{percent(interval[1])}"


def _published_text(entry: tuple | None) -> str:
    if entry is None:
        return ""
    p, r, f, source = entry
    return f"{p:.1f} / {r:.1f} / {f:.1f} ({source})"


def _numeric(text: str) -> bool:
    return text in ("", "–") or text.startswith("skipped") or text.replace(".", "", 1).isdigit()


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |"]
    numeric = [all(_numeric(row[k]) for row in rows if k < len(row)) for k in range(len(header))]
    out.append("|" + "|".join("---:" if n else "---" for n in numeric) + "|")
    out.extend("| " + " | ".join(row) + " |" for row in rows)
    return out


def to_markdown(benchmark: Benchmark, *, command: str, plot_name: str | None = None) -> str:
    """The tables: per dataset P/R/F1 at T = 2/3 and 1, the mean over datasets, by sequence."""
    lines = [
        "# Benchmark: F-formation detectors on the field's datasets",
        "",
        f"Command: `{command}`",
        "",
        "Protocol: the field's (GCFF's `ff_evalgroups`): per frame, singletons dropped, a true "
        "group matched by a detected group with |G∩D| / max(|G|, |D|) >= T; P and R are means "
        "over frames, F1 is the F1 of those means. Ground-truth members absent from a frame's "
        "features count as missed. Figures in %. The 95% CI of each F1 is a block bootstrap "
        "(each recording cut into 10 contiguous stretches resampled whole, 1,000 resamples, the "
        "same resamples for every detector on a dataset): neighbouring frames are near-duplicates, "
        "so resampling frames alone would make it too narrow.",
        "",
    ]
    splits = [d for d in benchmark.datasets if d.split == "test"]
    if splits:
        names = ", ".join(d.name for d in splits)
        lines += [
            f"{names}: only the test part of `reform.time_split` (train fraction "
            f"{splits[0].train_fraction:g}) is scored, the frames `reform-sim train --frames "
            "train` leaves out.",
            "",
        ]
    header = ["dataset", "frames", "detector", "P 2/3", "R 2/3", "F1 2/3", "95% CI 2/3"]
    header += ["P 1", "R 1", "F1 1", "95% CI 1", "published P / R / F1 at 2/3"]
    rows = []
    for dataset in benchmark.datasets:
        for detector in benchmark.detectors:
            cell = benchmark.cell(dataset, detector)
            if cell.scores is None:
                rows.append([dataset.label, "", detector.label, f"skipped: {cell.skipped}"])
                rows[-1] += [""] * (len(header) - len(rows[-1]))
                continue
            rows.append(
                [dataset.label, str(cell.scores.frames), detector.label]
                + _row(cell.scores.at["2/3"])
                + [_interval_text(cell.scores.f1_interval.get("2/3"))]
                + _row(cell.scores.at["1"])
                + [_interval_text(cell.scores.f1_interval.get("1"))]
                + [_published_text(benchmark.published(dataset, detector))]
            )
    lines += ["## Per dataset", "", *_table(header, rows), ""]

    mean_header = ["detector", "datasets", "P 2/3", "R 2/3", "F1 2/3", "P 1", "R 1", "F1 1"]
    lines += [
        "## Mean over datasets",
        "",
        "The plain mean of the per-dataset figures, over the datasets each detector ran on.",
        "",
        *_table(mean_header, _mean_rows(benchmark.means())),
        "",
    ]
    common = benchmark.common_datasets()
    if common and len(common) < len(benchmark.datasets):
        lines += [
            f"Over the datasets every detector ran on ({', '.join(common)}), comparable across "
            "rows:",
            "",
            *_table(mean_header, _mean_rows(benchmark.means(common))),
            "",
        ]

    sequence_rows = []
    for dataset in benchmark.datasets:
        for detector in benchmark.detectors:
            cell = benchmark.cell(dataset, detector)
            if cell.scores is None or len(cell.by_sequence) < 2 and not _original(dataset, cell):
                continue
            for sequence, scores in cell.by_sequence.items():
                original = ""
                if detector.spec == "gcff-own":
                    known = ORIGINAL_GCFF_OWN.get((dataset.name, sequence))
                    if known:
                        original = f"{known[2]:.1f} / {known[3]:.1f} ({known[4]})"
                sequence_rows.append(
                    [dataset.label, sequence, str(scores.frames), detector.label]
                    + _row(scores.at["2/3"])
                    + [percent(scores.at["1"][2]), original]
                )
    if sequence_rows:
        lines += [
            "## By sequence",
            "",
            "Datasets of several sequences, and the sequences whose original-code scores are "
            "known (GCFF with the sequence's own settings, the original MATLAB code under GNU "
            "Octave).",
            "",
            *_table(
                [
                    "dataset",
                    "sequence",
                    "frames",
                    "detector",
                    "P 2/3",
                    "R 2/3",
                    "F1 2/3",
                    "F1 1",
                    "original code F1 2/3 / F1 1",
                ],
                sequence_rows,
            ),
            "",
        ]
    lines += _temporal_lines(benchmark)
    if plot_name:
        lines += [f"![F1 at T = 2/3 and T = 1 per dataset]({plot_name})", ""]
    lines.append(f"Ran in {benchmark.seconds:.1f} s.")
    return "\n".join(lines) + "\n"


def seconds_text(value: float | None) -> str:
    """Seconds with one decimal, or a dash."""
    return "–" if value is None else f"{value:.1f}"


def _temporal_lines(benchmark: Benchmark) -> list[str]:
    """The "Groups in time" section: every cell's events scored in time (``--temporal``)."""
    rows = []
    tolerances = {}
    for dataset in benchmark.datasets:
        for detector in benchmark.detectors:
            cell = benchmark.cell(dataset, detector)
            temporal = cell.temporal
            if temporal is None:
                continue
            if "skipped" in temporal:
                rows.append([dataset.label, detector.label, f"skipped: {temporal['skipped']}"])
                rows[-1] += [""] * 6
                continue
            tolerances[dataset.label] = temporal["tolerance_s"]
            latency = temporal["latency_s"]
            rows.append(
                [
                    dataset.label,
                    detector.label,
                    f"{temporal['true_events']:,}",
                    percent(temporal["recall"]),
                    percent(temporal["precision"]),
                    seconds_text(latency["median"]),
                    seconds_text(latency["p95"]),
                    f"{temporal['false_events_per_minute']:.1f}",
                    f"{temporal['identity_switches']:,}",
                ]
            )
    if not rows:
        return []
    windows = ", ".join(f"{label} {value:g} s" for label, value in tolerances.items())
    header = ["dataset", "detector", "true events", "event recall", "event precision"]
    header += ["latency median s", "latency p95 s", "false events / min", "identity switches"]
    return [
        "## Groups in time",
        "",
        "Each detector's group events (forms, dissolves, joins, leaves, merges, splits; "
        "docs/guide/temporal.md) against the ground truth's on the same scored frames: a detected "
        "event matches a true one of the same kind whose group it matches at 2/3 within the "
        f"dataset's window ({windows}: 1 s, or the frame interval where longer). Recall and "
        "precision pooled over kinds, in %; latency of the matched events; false events per "
        "minute of recording (flicker); identity switches of the true groups' matched tracks.",
        "",
        *_table(header, rows),
        "",
    ]


def _mean_rows(means: Mapping[str, Mapping[str, Any]]) -> list[list[str]]:
    """The rows of a table of ``Benchmark.means``: a detector's label, its datasets, then P, R
    and F1 at T = 2/3 and at T = 1."""
    return [
        [label, str(entry["datasets"])] + _row(entry["2/3"]) + _row(entry["1"])
        for label, entry in means.items()
    ]


def _means_json(means: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """``Benchmark.means`` as the report's JSON: per detector, its datasets and a
    ``{"precision", "recall", "f1"}`` object (or None) per threshold."""
    return {
        label: {
            "datasets": entry["datasets"],
            **{
                f"T={t}": None
                if entry[t] is None
                else dict(zip(("precision", "recall", "f1"), entry[t], strict=True))
                for t in THRESHOLDS
            },
        }
        for label, entry in means.items()
    }


def _original(dataset: Any, cell: Cell) -> bool:
    return any((dataset.name, s) in ORIGINAL_GCFF_OWN for s in cell.by_sequence)


def to_json(benchmark: Benchmark, *, command: str) -> dict[str, Any]:
    """Every number of the report."""
    cells = []
    for dataset in benchmark.datasets:
        for detector in benchmark.detectors:
            cell = benchmark.cell(dataset, detector)
            published = benchmark.published(dataset, detector)
            cells.append(
                {
                    "dataset": dataset.label,
                    "detector": detector.label,
                    "skipped": cell.skipped,
                    "scores": None if cell.scores is None else cell.scores.to_json(),
                    "by_sequence": {s: v.to_json() for s, v in cell.by_sequence.items()},
                    "seconds": round(cell.seconds, 3),
                    **({} if cell.temporal is None else {"temporal": cell.temporal}),
                    "published_at_2/3": None
                    if published is None
                    else dict(zip(("precision", "recall", "f1", "source"), published, strict=True)),
                }
            )
    common = benchmark.common_datasets()
    return {
        "schema_version": JSON_SCHEMA_VERSION,
        "command": command,
        "datasets": [
            {
                "name": d.name,
                "label": d.label,
                "path": d.path,
                "split": d.split,
                "train_fraction": d.train_fraction if d.split == "test" else None,
            }
            for d in benchmark.datasets
        ],
        "detectors": [
            {"label": m.label, "spec": m.spec, "kind": m.kind} for m in benchmark.detectors
        ],
        "cells": cells,
        "mean_over_datasets": _means_json(benchmark.means()),
        "common_datasets": list(common),
        "mean_over_common_datasets": _means_json(benchmark.means(common)),
        "seconds": round(benchmark.seconds, 3),
    }


def plot(benchmark: Benchmark, path: str | Path) -> Path:
    """F1 at T = 2/3 and T = 1, a bar per detector for every dataset, as a PNG.

    Drawn on a bare matplotlib `Figure`, which writes PNG files through the Agg canvas: no
    pyplot, no backend chosen, and matplotlib imported only here, when a plot is drawn."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    datasets = [d.label for d in benchmark.datasets]
    n = len(benchmark.detectors)
    width = 0.8 / n
    x = np.arange(len(datasets))
    rows = (n + 2) // 3  # the legend below the panels, three detectors a row
    figure = Figure(figsize=(max(6.0, 1.2 * len(datasets) + 2), 4.0 + 0.22 * rows))
    panels = figure.subplots(1, len(THRESHOLDS), sharey=True)
    colours = colormaps["tab20"]
    for panel, threshold in zip(np.atleast_1d(panels), THRESHOLDS, strict=True):
        for k, detector in enumerate(benchmark.detectors):
            values = []
            for dataset in benchmark.datasets:
                cell = benchmark.cell(dataset, detector)
                values.append(np.nan if cell.scores is None else cell.scores.at[threshold][2])
            colour = colours(k / max(n - 1, 1)) if n > 10 else f"C{k}"  # none repeated
            panel.bar(
                x + (k - (n - 1) / 2) * width, values, width, label=detector.label, color=colour
            )
        panel.set_xticks(x, datasets, rotation=30, ha="right", fontsize=8)
        panel.set_title(f"F1 at T = {threshold}")
        panel.set_ylim(0.0, 1.0)
        panel.grid(axis="y", alpha=0.3)
    np.atleast_1d(panels)[0].set_ylabel("F1 (frame-mean protocol)")
    handles, labels = np.atleast_1d(panels)[0].get_legend_handles_labels()
    figure.legend(handles, labels, fontsize=7, loc="lower center", ncol=3, frameon=False)
    figure.tight_layout(rect=(0.0, 0.22 * rows / (4.0 + 0.22 * rows) + 0.02, 1.0, 1.0))
    target = Path(path)
    with atomic_path(target) as tmp:
        figure.savefig(tmp, format="png", dpi=PLOT_DPI, bbox_inches="tight")
    return target


def _slug(label: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "-" for c in label).strip("-")


def record(
    benchmark: Benchmark, folder: str | Path, *, progress: Callable[[str], None] | None = None
) -> dict[str, Path]:
    """One ``.rrd`` per dataset: its scored frames, the ground truth and every detector's groups
    with their mistakes, and the running scores (`Benchmark.recorded`: the test part where a
    detector learns on the rest). Returns dataset label -> path; ``progress`` is
    called with a line as each recording is written."""
    from sim.recording import record_evaluation  # here: a run without recordings needs no Rerun

    folder = Path(folder)
    written = {}
    for dataset in benchmark.datasets:
        frames, predictions = benchmark.recorded(dataset)
        if not frames:
            continue
        path = folder / f"{_slug(dataset.name)}.rrd"
        record_evaluation(
            path, frames, predictions, name=f"benchmark-{dataset.name}", dataset=dataset.name
        )
        written[dataset.label] = path
        if progress is not None:
            progress(f"recorded {dataset.name}: {path}")
    return written


def write_report(
    benchmark: Benchmark,
    out_dir: str | Path,
    *,
    command: str,
    recordings: bool = True,
    progress: Callable[[str], None] | None = None,
) -> Mapping[str, Path]:
    """Writes ``benchmark.md``, ``benchmark.json``, ``benchmark.png`` and, with ``recordings``,
    ``recordings/<dataset>.rrd`` into ``out_dir`` (atomically). Returns what was written;
    ``progress`` is called with a line as each recording is written (they take seconds)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {"plot": plot(benchmark, out / PLOT_NAME)}
    written["markdown"] = write_markdown(
        out / MARKDOWN_NAME, to_markdown(benchmark, command=command, plot_name=PLOT_NAME)
    )
    written["json"] = write_json(out / JSON_NAME, to_json(benchmark, command=command), indent=1)
    if recordings:
        for label, path in record(benchmark, out / RECORDINGS, progress=progress).items():
            written[f"recording:{label}"] = path
    return written

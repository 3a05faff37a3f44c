"""Paper-style tables of evaluation results, as Markdown or as plain text.

The functions read the JSON-ready dict of :meth:`reform.metrics.Evaluation.to_json` (the schema
in docs/json-schema.md), so a table can be rebuilt from a saved ``--json`` file. Scores are
printed as percentages with one decimal, as in the REFORM paper's tables.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping, Sequence
from typing import Any

__all__ = [
    "MISSING",
    "STYLES",
    "command_block",
    "format_comparison",
    "format_report",
    "markdown_table",
    "percent",
    "render_table",
]

STYLES = ("text", "markdown")
MISSING = "-"  # what a table shows for a score that does not exist
_WIDTH = 100  # characters per line of prose


def percent(value: float | None, *, missing: str = MISSING) -> str:
    """A fraction as a percentage with one decimal (``0.8125`` -> ``"81.2"``); ``missing`` for
    None, NaN or an infinity."""
    if value is None or not math.isfinite(value):
        return missing
    return f"{100.0 * value:.1f}"


def command_block(command: str) -> list[str]:
    """Markdown lines naming the command that produced a results page (and regenerates it)."""
    return ["Produced by:", "", "```sh", command, "```", ""]


def _count(value: int) -> str:
    return f"{value:,}"


def render_table(
    headers: Sequence[str], rows: Sequence[Sequence[str]], *, style: str = "text"
) -> str:
    """A table of strings; the first column left-aligned, the others right-aligned.

    Args:
        headers: column titles.
        rows: rows of cells, each as many as ``headers``.
        style: ``"markdown"`` (a GitHub table) or ``"text"`` (aligned columns, a rule below
            the header).
    """
    if style not in STYLES:
        raise ValueError(f"style must be one of {STYLES}, got {style!r}")
    for r, row in enumerate(rows):
        if len(row) != len(headers):
            raise ValueError(f"rows[{r}] must have {len(headers)} cells, got {len(row)}")
    widths = [max(len(str(c)) for c in column) for column in zip(headers, *rows, strict=True)]

    def line(cells: Sequence[str]) -> str:
        padded = [
            str(c).ljust(w) if i == 0 else str(c).rjust(w)
            for i, (c, w) in enumerate(zip(cells, widths, strict=True))
        ]
        return ("| " + " | ".join(padded) + " |") if style == "markdown" else "  ".join(padded)

    if style == "markdown":
        rule = (
            "|"
            + "|".join(
                ":" + "-" * (w + 1) if i == 0 else "-" * (w + 1) + ":" for i, w in enumerate(widths)
            )
            + "|"
        )
    else:
        rule = "  ".join("-" * w for w in widths)
    return "\n".join([line(headers), rule, *(line(row) for row in rows)])


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A page's lines for a GitHub table (`render_table`) and the blank line after it."""
    return [render_table(headers, rows, style="markdown"), ""]


def _title(result: Mapping[str, Any], style: str) -> str:
    sequences = result.get("sequences") or {}
    detail = ", ".join(f"{name} {_count(n)}" for name, n in sequences.items())
    text = (
        f"{result['detector']} on {result['dataset']}: {_count(result['frames'])} annotated frames"
        + (f" ({detail})" if len(sequences) > 1 else "")
    )
    return f"### {text}" if style == "markdown" else text


def format_report(result: Mapping[str, Any], *, style: str = "text") -> str:
    """The full report of one detector on one dataset.

    Sections: pairwise accuracy; precision, recall and F1 at each threshold under the frame-mean
    protocol and micro-averaged, with the pooled TP/FP/FN; recall by true-group size and
    precision by detected-group size.

    Args:
        result: ``Evaluation.to_json(...)`` output (or a loaded ``--json`` file).
        style: ``"text"`` or ``"markdown"``.
    """
    if style not in STYLES:
        raise ValueError(f"style must be one of {STYLES}, got {style!r}")
    thresholds = list(result["thresholds"])
    pairs = result["pairs"]
    accuracy = (
        f"Pairwise accuracy: {percent(result['pairwise_accuracy'])} % "
        f"({_count(pairs['correct'])} of {_count(pairs['total'])} pairs labelled correctly; "
        f"{_count(pairs['true_together'])} pairs together in the ground truth, "
        f"{_count(pairs['predicted_together'])} predicted together)."
    )
    protocol = (
        "Protocol: GCFF's ff_evalgroups. Singletons dropped; a true group G is matched when a "
        "detected group D has |G∩D|/max(|G|,|D|) >= T. P, R: means of the per-frame precision "
        "and recall; F1 of those means. Micro: TP, FP, FN summed over frames."
    )
    if all(result[t]["micro"]["tp"] + result[t]["micro"]["fp"] == 0 for t in thresholds):
        protocol += (
            " No F-formation was detected: precision is 100 by the protocol's convention "
            "(a frame with no detection has P = 1)."
        )
    scores = render_table(
        ["T", "P", "R", "F1", "micro P", "micro R", "micro F1", "TP", "FP", "FN"],
        [
            [
                t,
                percent(result[t]["precision"]),
                percent(result[t]["recall"]),
                percent(result[t]["f1"]),
                percent(result[t]["micro"]["precision"]),
                percent(result[t]["micro"]["recall"]),
                percent(result[t]["micro"]["f1"]),
                _count(result[t]["micro"]["tp"]),
                _count(result[t]["micro"]["fp"]),
                _count(result[t]["micro"]["fn"]),
            ]
            for t in thresholds
        ],
        style=style,
    )
    parts = [_title(result, style), "", _wrap(accuracy), "", scores, "", _wrap(protocol)]

    by_sequence = result.get("by_sequence") or {}
    if by_sequence:
        headers = ["sequence", "frames", "pair acc."]
        for t in thresholds:
            headers += [f"P@{t}", f"R@{t}", f"F1@{t}"]
        rows = []
        for name, summary in by_sequence.items():
            row = [name, _count(summary["frames"]), percent(summary["pairwise_accuracy"])]
            for t in thresholds:
                row += [percent(summary[t][k]) for k in ("precision", "recall", "f1")]
            rows.append(row)
        parts += [
            "",
            "By sequence (frame-mean protocol):",
            "",
            render_table(headers, rows, style=style),
        ]

    sizes = sorted({b["size"] for t in thresholds for b in result[t]["by_size"]})
    by_size = {t: {b["size"]: b for b in result[t]["by_size"]} for t in thresholds}
    size_rows = []
    for size in sizes:
        entry = by_size[thresholds[0]].get(size, {})
        size_rows.append(
            [
                str(size),
                _count(entry.get("true_groups", 0)),
                *(percent(by_size[t].get(size, {}).get("recall")) for t in thresholds),
                _count(entry.get("detected_groups", 0)),
                *(percent(by_size[t].get(size, {}).get("precision")) for t in thresholds),
            ]
        )
    size_note = (
        "By group size, pooled over frames: R@T = share of the true groups of that size that "
        "were matched; P@T = share of the detected groups of that size that matched a true group."
    )
    parts += ["", _wrap(size_note), ""]
    if size_rows:
        headers = ["size", "true groups", *(f"R@{t}" for t in thresholds)]
        headers += ["detected", *(f"P@{t}" for t in thresholds)]
        parts.append(render_table(headers, size_rows, style=style))
    else:
        parts.append("(no F-formations, true or detected)")
    temporal = result.get("temporal")
    if temporal:
        parts += ["", *format_temporal(temporal, style=style)]
    return "\n".join(parts) + "\n"


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def format_temporal(temporal: Mapping[str, Any], *, style: str = "text") -> list[str]:
    """The lines of a temporal evaluation (`reform.TemporalEvaluation.to_json`): events per kind
    found and invented, latency, flicker and identity switches."""
    intervals = temporal.get("intervals") or {}

    def spread(name: str, show) -> str:
        interval = intervals.get(name)
        if not interval:
            return ""
        return f" ({show(interval['low'])} to {show(interval['high'])})"

    rows = [
        [
            kind,
            _count(scores["true_events"]),
            _count(scores["detected_events"]),
            _count(scores["matched"]),
            percent(scores["recall"]),
            percent(scores["precision"]),
        ]
        for kind, scores in temporal["by_kind"].items()
    ]
    rows.append(
        [
            "all",
            _count(temporal["true_events"]),
            _count(temporal["detected_events"]),
            _count(temporal["latency_s"]["matched"]),
            percent(temporal["recall"]),
            percent(temporal["precision"]),
        ]
    )
    latency = temporal["latency_s"]
    summary = (
        f"Latency of the matched events: median {_seconds(latency['median'])} s"
        f"{spread('latency_median_s', _seconds)}, 95th percentile {_seconds(latency['p95'])} s"
        f"{spread('latency_p95_s', _seconds)}. False events: {_count(temporal['false_events'])}"
        f", {temporal['false_events_per_minute']:.2f} per minute"
        f"{spread('false_events_per_minute', lambda v: f'{v:.2f}')} over "
        f"{temporal['minutes']:.1f} min. Identity switches: "
        f"{_count(temporal['identity_switches'])}."
    )
    note = (
        f"Group events (docs/guide/temporal.md): a detected event matches a true event of the "
        f"same kind within {temporal['tolerance_s']:g} s whose group it matches at "
        f"{temporal['member_threshold']} (the same person for joins and leaves), one to one."
    )
    return [
        "Groups in time:",
        "",
        render_table(
            ["event", "true", "detected", "matched", "recall", "precision"], rows, style=style
        ),
        "",
        _wrap(summary),
        "",
        _wrap(note),
    ]


def _wrap(text: str) -> str:
    return textwrap.fill(text, width=_WIDTH, break_on_hyphens=False)


def format_comparison(results: Sequence[Mapping[str, Any]], *, style: str = "text") -> str:
    """The paper's table: one row per result, pairwise accuracy and P/R/F1 at each threshold.

    Args:
        results: ``Evaluation.to_json(...)`` outputs, e.g. several detectors on one dataset.
        style: ``"text"`` or ``"markdown"``.
    """
    if not results:
        raise ValueError("results must hold at least one evaluation, got none")
    thresholds = list(results[0]["thresholds"])
    headers = ["detector", "dataset", "frames", "pair acc."]
    for t in thresholds:
        headers += [f"P@{t}", f"R@{t}", f"F1@{t}"]
    rows = []
    for result in results:
        row = [
            str(result["detector"]),
            str(result["dataset"]),
            _count(result["frames"]),
            percent(result["pairwise_accuracy"]),
        ]
        for t in thresholds:
            scores = result.get(t)
            row += (
                [MISSING] * 3
                if scores is None
                else [percent(scores[k]) for k in ("precision", "recall", "f1")]
            )
        rows.append(row)
    return render_table(headers, rows, style=style) + "\n"

"""The report of ``reform-sim experiment temporal``: Markdown, JSON and a plot (flicker against
event recall, one point per detector and dataset)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sim.experiments.benchmark import percent
from sim.experiments.benchmark_report import seconds_text
from sim.experiments.benchmark_report import to_json as benchmark_json
from sim.experiments.figures import pyplot, save_png
from sim.experiments.temporal import (
    MAX_ADDED_LATENCY_S,
    MAX_FLICKER_RATIO,
    PARTY,
    TemporalResult,
)

__all__ = ["figure", "to_json", "to_markdown"]


def _interval(temporal: dict[str, Any], name: str, show) -> str:
    interval = (temporal.get("intervals") or {}).get(name)
    if not interval or interval.get("low") is None:
        return ""
    return f" ({show(interval['low'])}–{show(interval['high'])})"


def _rows(result: TemporalResult, dataset: Any) -> list[list[str]]:
    rows = []
    for detector in result.benchmark.detectors:
        cell = result.benchmark.cell(dataset, detector)
        temporal = cell.temporal or {}
        if cell.scores is None or "skipped" in temporal or not temporal:
            why = cell.skipped or temporal.get("skipped", "")
            rows.append([detector.label, f"skipped: {why}", *[""] * 6])
            continue
        f1 = cell.scores.at["2/3"][2]
        ci = cell.scores.f1_interval.get("2/3")
        latency = temporal["latency_s"]
        rows.append(
            [
                detector.label,
                f"{percent(f1)}" + ("" if ci is None else f" ({percent(ci[0])}–{percent(ci[1])})"),
                percent(temporal["recall"]) + _interval(temporal, "recall", percent),
                percent(temporal["precision"]) + _interval(temporal, "precision", percent),
                seconds_text(latency["median"])
                + _interval(temporal, "latency_median_s", seconds_text),
                seconds_text(latency["p95"]),
                f"{temporal['false_events_per_minute']:.1f}"
                + _interval(temporal, "false_events_per_minute", lambda v: f"{v:.1f}"),
                f"{temporal['identity_switches']:,}",
            ]
        )
    return rows


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    return lines + ["| " + " | ".join(row) + " |" for row in rows]


def to_markdown(result: TemporalResult, *, command: str, figure: str | None = None) -> str:
    """The results page."""
    party = result.party
    goals = result.goals
    met = sum(goal.met for goal in goals)
    lines = [
        "# Groups in time: events, latency and flicker of every detector",
        "",
        "Produced by:",
        "",
        "```sh",
        command,
        "```",
        "",
        f"The default party: {party['episodes']} episodes of `{party['scenario']}` at its default "
        f"options, {party['duration_s']:g} s each at {party['rate_hz']:g} Hz "
        f"({party['frames']:,} frames, {party['people_per_frame']:.1f} people a frame; master "
        f"seed {party['seed']}); the same parties with scripted changes "
        f"(`{', '.join(f'{k}={v:g}' for k, v in party['scripted_options'].items())}`: latecomers "
        "walking up to groups, members drifting away, groups walking over to merge), whose "
        "joins and leaves the default party's own comings and goings rarely make; and every "
        "real dataset given, each scored as `reform-sim "
        "benchmark --temporal` scores it: detectors that learn are fitted on the first 60 % of "
        "each recording and scored on the rest, the others on every frame (SALSA: its test "
        "part only). Definitions: [Groups in time](../guide/temporal.md). Events match within "
        "1 s, or a dataset's frame interval where longer. Intervals: 95 %, F1 by block "
        "bootstrap, the temporal figures by bootstrap over sequences (episodes, sessions). "
        f"The run took {result.seconds / 60:.1f} minutes.",
        "",
        "## The filters on the default party",
        "",
        f"A filter meets the goal when its false events per minute are at most "
        f"{MAX_FLICKER_RATIO:g} of the detector's it wraps, its median latency at most "
        f"{MAX_ADDED_LATENCY_S:g} s later, and its frame F1 at T = 2/3 not lower. Both run at "
        "their catalogue defaults (`smoothed`: GCFF voted over 2 s; `hysteresis`: REFORM's "
        "pair probabilities switched at 0.7 and 0.3), fixed before this run.",
        "",
        f"**Goals met: {met} of {len(goals)}.**",
        "",
        *_table(
            [
                "filter",
                "wraps",
                "false events / min",
                "median latency s",
                "F1 2/3",
                "met",
            ],
            [
                [
                    goal.filter,
                    goal.detector,
                    f"{goal.flicker[0]:.1f} → {goal.flicker[1]:.1f}",
                    f"{seconds_text(goal.latency[0])} → {seconds_text(goal.latency[1])}",
                    f"{percent(goal.f1[0])} → {percent(goal.f1[1])}",
                    "yes" if goal.met else "**no**",
                ]
                for goal in goals
            ],
        ),
        "",
    ]
    header = [
        "detector",
        "F1 2/3",
        "event recall",
        "event precision",
        "latency median s",
        "latency p95 s",
        "false events / min",
        "identity switches",
    ]
    for dataset in result.benchmark.datasets:
        lines += [f"## {dataset.label}", "", *_table(header, _rows(result, dataset)), ""]
    if figure:
        lines += [f"![false events per minute against event recall]({figure})", ""]
    return "\n".join(lines)


def to_json(result: TemporalResult, *, command: str) -> dict[str, Any]:
    """Every number of the report: the benchmark's (cells with ``temporal``), the party and the
    filters' goals."""
    return {
        "kind": "reform-sim/temporal-experiment",
        "schema_version": 1,
        "party": dict(result.party),
        "goals": [goal.to_json() for goal in result.goals],
        "benchmark": benchmark_json(result.benchmark, command=command),
        "seconds": round(result.seconds, 3),
    }


def figure(result: TemporalResult, path: str | Path) -> Path:
    """False events per minute against event recall, one point per detector, one panel per
    dataset."""
    plt = pyplot()
    datasets = result.benchmark.datasets
    panels = len(datasets)
    fig, axes = plt.subplots(1, panels, figsize=(4.2 * panels, 4.2), squeeze=False)
    colours = plt.get_cmap("tab20")
    for panel, dataset in zip(axes[0], datasets, strict=True):
        for k, detector in enumerate(result.benchmark.detectors):
            temporal = result.benchmark.cell(dataset, detector).temporal or {}
            if not temporal or "skipped" in temporal or temporal.get("recall") is None:
                continue
            panel.scatter(
                100 * temporal["recall"],
                temporal["false_events_per_minute"],
                color=colours(k % 20),
                label=detector.label if dataset.label == PARTY or panels == 1 else None,
                s=28,
            )
        panel.set_title(dataset.label)
        panel.set_xlabel("event recall, %")
        panel.set_xlim(0, 100)
    axes[0][0].set_ylabel("false events per minute")
    fig.legend(loc="lower center", ncol=3, fontsize=7, frameon=False)
    rows = (len(result.benchmark.detectors) + 2) // 3
    fig.subplots_adjust(bottom=0.18 + 0.035 * rows, top=0.9, wspace=0.25)
    return save_png(fig, path)

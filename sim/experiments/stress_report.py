"""The stress tests' report: Markdown with tables and PNG plots, JSON, and a Rerun recording.

:func:`write_report` writes, into one folder, ``stress.md`` (the command that regenerates it,
the protocol, a summary and, per axis, a plot and tables of F1 with 95 % bootstrap intervals),
``stress.json`` (every number) and ``stress-<axis>.png`` (F1 against the axis at T = 2/3 and
T = 1, intervals shaded). :func:`log_results` puts the curves into a Rerun recording
(``sim.recording.log_stress_curves``), one bar chart per axis and threshold.

Every detector of the run is reported (``StressResults.detectors``): the built-in ones in the
order of :data:`sim.experiments.stress.DETECTOR_LABELS`, then the plugins given to
``reform-sim stress --detector`` in the order they were given, labelled by their names.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from reform.atomic import atomic_path
from sim.experiments.figures import pyplot
from sim.experiments.report_files import write_json, write_markdown
from sim.experiments.stress import (
    AXES,
    DETECTOR_LABELS,
    GCFF,
    THRESHOLDS,
    StressAxis,
    StressResults,
    sensor_description,
)
from sim.experiments.tables import command_block, percent, render_table
from sim.recording import RecordingTarget

__all__ = [
    "MARKDOWN_NAME",
    "JSON_NAME",
    "log_results",
    "plot_axis",
    "plot_path",
    "record",
    "recording_names",
    "to_markdown",
    "write_report",
]

MARKDOWN_NAME = "stress.md"
JSON_NAME = "stress.json"
PLOT_DPI = 110  # dots per inch of the PNG plots
PLOT_SIZE_IN = (10.0, 3.6)  # inches, one axis: two panels side by side
_THRESHOLD_TEXT = {"2/3": "T = 2/3", "1": "T = 1"}


def _cell(interval: Any) -> str:
    if not math.isfinite(interval.value):
        return "-"
    return f"{percent(interval.value)} [{percent(interval.low)}, {percent(interval.high)}]"


def plot_path(out_dir: str | Path, axis: str) -> Path:
    """Where the plot of ``axis`` goes in ``out_dir``."""
    return Path(out_dir) / f"stress-{axis}.png"


def _report_labels(detectors: Mapping[str, str] | None = None) -> dict[str, str]:
    """The detectors a report shows, name -> label, in its order.

    The built-in detectors of :data:`DETECTOR_LABELS` always, first and in that order (labelled
    as ``detectors`` labels them, else as there); then every other detector of ``detectors``
    (plugins), in its order. A plugin whose label another detector already has is told apart
    by its name.

    Args:
        detectors: the run's detectors, name -> label (`StressResults.detectors`); None: the
            built-in ones.
    """
    given = dict(detectors or {})
    labels = {name: given.get(name, label) for name, label in DETECTOR_LABELS.items()}
    for name, label in given.items():
        if name in labels:
            continue
        taken = set(labels.values())
        labels[name] = label if label not in taken else f"{label} ({name})"
    return labels


def plot_axis(
    axis: StressAxis, path: str | Path, *, detectors: Mapping[str, str] | None = None
) -> Path:
    """F1 of every detector along ``axis`` at T = 2/3 and T = 1, intervals shaded, as a PNG.

    Args:
        axis: the axis's points.
        path: the PNG to write.
        detectors: the detectors to draw, name -> label (`StressResults.detectors`): the
            built-in ones first, in their colours, then the others (plugins, dash-dotted);
            None: the built-in ones. Those without scores on the axis are left out.
    """
    plt = pyplot()
    x = axis.x
    categorical = axis.name == "sensor"
    positions = np.arange(x.size) if categorical else x
    labels = _report_labels(detectors)
    figure, panels = plt.subplots(1, len(THRESHOLDS), figsize=PLOT_SIZE_IN, sharey=True)
    for panel, threshold in zip(np.atleast_1d(panels), THRESHOLDS, strict=True):
        for index, detector in enumerate(labels):
            value, low, high = axis.curve(detector, threshold)
            if np.all(np.isnan(value)):
                continue
            colour = f"C{index}"
            style = _line_style(detector)
            panel.plot(
                positions,
                value,
                style,
                marker="o",
                ms=3,
                color=colour,
                label=labels[detector],
            )
            panel.fill_between(positions, low, high, color=colour, alpha=0.15, linewidth=0)
        panel.set_title(f"{axis.title}: F1 at {_THRESHOLD_TEXT[threshold]}")
        panel.set_xlabel(axis.x_label if not categorical else "sensor")
        if categorical:
            panel.set_xticks(positions, [p.label for p in axis.points])
        panel.set_ylim(0.0, 1.02)
        panel.grid(alpha=0.3)
    np.atleast_1d(panels)[0].set_ylabel("F1 (95% bootstrap interval)")
    np.atleast_1d(panels)[-1].legend(fontsize=7, loc="lower left")
    figure.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        figure.savefig(tmp, dpi=PLOT_DPI, format="png")
    plt.close(figure)
    return path


def _line_style(detector: str) -> str:
    """GCFF dashed, REFORM solid, plugins dash-dotted."""
    if detector == GCFF:
        return "--"
    return "-" if detector in DETECTOR_LABELS else "-."


def _axis_tables(axis: StressAxis, labels: Mapping[str, str]) -> list[str]:
    detectors = [d for d in labels if any(d in p.scores for p in axis.points)]
    context = [
        "level",
        "episodes",
        "frames",
        "guests/m²",
        "people/frame",
        "F-formations/frame",
        "mean size",
    ]
    lines = []
    rows = [
        [
            p.label if axis.name != "sensor" else f"{p.label} ({sensor_description(p.label)})",
            str(p.episodes),
            str(p.frames),
            "-" if not math.isfinite(p.people_per_m2) else f"{p.people_per_m2:.2f}",
            "-" if not math.isfinite(p.people_per_frame) else f"{p.people_per_frame:.1f}",
            "-" if not math.isfinite(p.fformations_per_frame) else f"{p.fformations_per_frame:.2f}",
            "-" if not math.isfinite(p.fformation_size) else f"{p.fformation_size:.2f}",
        ]
        for p in axis.points
    ]
    lines += [render_table(context, rows, style="markdown"), ""]
    for threshold in THRESHOLDS:
        headers = ["level", *(labels[d] for d in detectors)]
        rows = [
            [
                p.label,
                *(_cell(p.scores[d][threshold].f1) if d in p.scores else "-" for d in detectors),
            ]
            for p in axis.points
        ]
        lines += [
            f"F1 at {_THRESHOLD_TEXT[threshold]}, % [95% interval]:",
            "",
            render_table(headers, rows, style="markdown"),
            "",
        ]
    notes = [n for p in axis.points for n in p.notes]
    if notes:
        lines += [
            f"{len(notes)} test part(s) could not be laid out by mingle's planner with their "
            "first seed and were drawn again with another (see stress.json).",
            "",
        ]
    return lines


def _summary(results: StressResults) -> list[str]:
    labels = _report_labels(results.detectors)
    lines = [
        "| axis | from → to | " + " | ".join(labels.values()) + " |",
        "|:--|:--|" + "--:|" * len(labels),
    ]
    for axis in results.axes:
        first, last = axis.points[0], axis.points[-1]
        cells = []
        for detector in labels:
            a = first.scores.get(detector, {}).get("2/3")
            b = last.scores.get(detector, {}).get("2/3")
            if a is None or b is None:
                cells.append("-")
                continue
            cells.append(
                f"{percent(a.f1.value)} → {percent(b.f1.value)} "
                f"({100.0 * (b.f1.value - a.f1.value):+.1f})"
            )
        lines.append(f"| {axis.title} | {first.label} → {last.label} | " + " | ".join(cells) + " |")
    return lines


def _temporal_summary(results: StressResults) -> list[str]:
    """With ``--temporal``: each detector's false events per minute and event recall at the
    first and last level of every axis."""
    if not any(point.temporal for axis in results.axes for point in axis.points):
        return []
    labels = _report_labels(results.detectors)

    def show(temporal: Mapping[str, Any] | None) -> str:
        if not temporal:
            return "-"
        flicker = temporal["false_events_per_minute"]
        recall = temporal["recall"]
        return (
            f"{'-' if flicker is None else f'{flicker:.1f}'} / "
            f"{'-' if recall is None else percent(recall)}"
        )

    lines = [
        "## Groups in time (false events per minute / event recall %, first → last level)",
        "",
        "Each detector's group events (docs/guide/temporal.md) against the truth's, matched "
        "within 1 s or the frame interval where longer, pooled over a point's episodes: false "
        "events per minute (flicker) and the share of true events found. Every point's figures, "
        "with latency and identity switches, are in stress.json (`temporal`). Under dropout "
        "the truth, restricted to the people a frame holds, changes whenever someone drops out "
        "or comes back, and a detector that sees the same people follows: its event recall "
        "there measures that, not conversation.",
        "",
        "| axis | from → to | " + " | ".join(labels.values()) + " |",
        "|:--|:--|" + "--:|" * len(labels),
    ]
    for axis in results.axes:
        first, last = axis.points[0], axis.points[-1]
        cells = [f"{show(first.temporal.get(d))} → {show(last.temporal.get(d))}" for d in labels]
        lines.append(f"| {axis.title} | {first.label} → {last.label} | " + " | ".join(cells) + " |")
    return [*lines, ""]


def _minutes(seconds: float) -> str:
    return f"{seconds / 60.0:.1f} min" if seconds >= 60 else f"{seconds:.0f} s"


def to_markdown(results: StressResults, *, command: str, plots: Mapping[str, str]) -> str:
    """The report as Markdown; ``plots`` maps an axis name to its PNG's path relative to it."""
    grid = results.grid
    training = results.training
    timings = results.timings
    env = results.environment
    lines = [
        "# Stress tests: REFORM and GCFF under tracking errors, crowds and the robot's sensor",
        "",
        *command_block(command),
        f"Grid `{results.grid_name}`, master seed {results.seed}, {results.jobs} worker "
        f"process(es) on a {env.get('cores', '?')}-core machine (load average "
        f"{env.get('load_average_start', '?')} when the run started). Wall time "
        f"{_minutes(timings.get('total', math.nan))}: "
        + ", ".join(f"{k} {_minutes(v)}" for k, v in timings.items() if k != "total")
        + f". CPU time of all tasks: {_minutes(env.get('cpu_s', math.nan))} (on an otherwise idle "
        f"machine the wall time approaches CPU time / workers; the load average says how busy "
        f"this one was: {env.get('load_average_end', '?')} at the end).",
        "",
        "## Protocol",
        "",
    ]
    if training.get("source") == "synthetic":
        lines += [
            f"- **Training (synthetic, once).** REFORM's three classifiers (weighted KNN, bagged "
            f"trees, logistic regression; `reform.classifiers`) are fitted on "
            f"{training['frames']:,} frames ({training['pairs']:,} pairs, "
            f"{training['together_pairs']:,} together) of {grid.train_episodes} episode(s) each "
            f"of {' and '.join(training['scenarios'])} at default options "
            f"({grid.train_duration_s:g} s at {grid.train_rate_hz:g} Hz). GCFF is tuned on "
            f"{training['gcff_tuning_frames']} of those frames (grid search, F1 at T = 2/3, "
            f"strides {list(grid.gcff_stride_grid_m)} m, mdl {list(grid.gcff_mdl_grid_m2)} m²): "
            f"stride {training['gcff_stride_m']:g} m, mdl {training['gcff_mdl_m2']:g} m². "
            "No real data is used. Training and test episodes take their seeds from different "
            "spawn keys of the master seed (`reform.seeding`: roles STRESS_TRAIN and "
            "STRESS_TEST), so they never share one.",
        ]
    else:
        lines += ["- **Detectors** were given, already fitted."]
    lines += [
        f"- **Test parties.** Each point is scored on {grid.seeds} episode(s) of `mingle` "
        f"(18 guests at 0.4 per m², SALSA-like, unless the axis changes it), "
        f"{grid.duration_s:g} s at {grid.rate_hz:g} Hz. Position noise, orientation noise and "
        "dropouts (`reform.perturb.Perturbation`) are applied to the same episodes at every "
        "level with the same random numbers (common random numbers); the other axes simulate "
        "a new episode per level with the same seeds. The ground truth of a perturbed or "
        "observed frame is the truth restricted to the people it holds.",
        "- **Scores.** The field's protocol (`reform.metrics.evaluate`, GCFF's "
        "`ff_evalgroups`): per frame P and R of the groups of two or more, F1 of the frame "
        "means, at T = 2/3 (the paper's setting) and T = 1 (exact). 95 % intervals: two-stage "
        f"bootstrap, {grid.resamples} resamples of episodes then frames within them "
        "(`reform.bootstrap`), the same resamples for every detector at a point.",
        "- **Sensor levels.** "
        + "; ".join(f"`{name}`: {sensor_description(name)}" for name in grid.sensors)
        + ". The robot watches from the west wall and is part of every frame.",
        "",
        "## Summary (F1 at T = 2/3, %, first → last level)",
        "",
        *_summary(results),
        "",
        *_temporal_summary(results),
        *_reading_notes(results),
    ]
    for axis in results.axes:
        lines += [f"## {axis.title}", "", axis.description, ""]
        if axis.name in plots:
            lines += [f"![{axis.title}]({plots[axis.name]})", ""]
        lines += _axis_tables(axis, _report_labels(results.detectors))
    return "\n".join(lines).rstrip() + "\n"


# Notes on reading the curves, each shown when one of its axes ran.
_READING_NOTES = (
    (
        ("dropout",),
        "**Dropout** removes people and restricts the truth to those kept: a group that loses "
        "members is still to be found, smaller, and a group left with one person is no longer "
        "an F-formation. The detector is not blamed for people it never saw, so the curve "
        "measures whether partial groups are still recognised (F1 at T = 1 can even rise: "
        "smaller groups are easier to match exactly).",
    ),
    (
        ("sensor",),
        "**Sensor** levels change the question as well as the difficulty: the head sensor "
        "sees a handful of the guests (see people per frame), so its frames hold fewer and "
        "smaller groups, cut by the edge of the field of view.",
    ),
    (
        ("density",),
        "**Density** stops at 0.5 guests per m²: in a smaller room `mingle`'s planner cannot "
        "lay out 18 guests (at 0.6 per m² no seed works). Near the limit some seeds fail and "
        "are drawn again, so those points hold the parties that fit (the tables count the "
        "redraws).",
    ),
    (
        ("groups", "group-size"),
        "**Number of groups** grows the party in a room sized for 0.4 guests per m², and "
        "**group size** keeps 18 guests there; `mingle` enlarges a room a drawn party does not "
        "fit, so read the density they ran at in the guests/m² column.",
    ),
    (
        ("crowd",),
        "**Crowd size** scores a `concourse`: walkers crossing and a queue beside the groups "
        "standing aside. Walkers and queuers are singletons in the truth, so a detector that "
        "groups a queue or people passing close loses precision there.",
    ),
    (
        tuple(name for name, info in AXES.items() if info.kind == "scene"),
        "Scene axes draw a new party per level with the same seeds, so their levels differ "
        "in the whole party, not only in the option; perturbation axes change nothing but "
        "the tracking errors.",
    ),
)


def _reading_notes(results: StressResults) -> list[str]:
    ran = {axis.name for axis in results.axes}
    notes = [f"- {text}" for axes, text in _READING_NOTES if ran.intersection(axes)]
    return ["Reading the curves:", "", *notes, ""] if notes else []


def recording_names(results: StressResults) -> list[str]:
    """The names :func:`log_results` logs curves under (for the blueprint)."""
    return [f"{axis.name}-{_slug(t)}" for axis in results.axes for t in THRESHOLDS]


def _slug(threshold: str) -> str:
    return "t" + threshold.replace("/", "of")


def log_results(rec: Any, results: StressResults) -> None:
    """Every axis's F1 curves, at each threshold, as stress bar charts in ``rec``."""
    from sim.recording import log_stress_curves  # here: a report without a recording needs no Rerun

    labels = _report_labels(results.detectors)
    for axis in results.axes:
        for threshold in THRESHOLDS:
            curves = {
                label: np.nan_to_num(axis.curve(d, threshold)[0], nan=0.0)
                for d, label in labels.items()
            }
            log_stress_curves(
                rec,
                axis.x,
                curves,
                x_label=f"{axis.x_label}; F1 at {_THRESHOLD_TEXT[threshold]}",
                name=f"{axis.name}-{_slug(threshold)}",
            )


def write_report(
    results: StressResults,
    out_dir: str | Path,
    *,
    command: str,
    save: RecordingTarget | str | Path | None = None,
) -> dict[str, Path]:
    """Writes the Markdown report, the JSON, the plots and, with ``save``, the curves as a
    Rerun recording (a ``.rrd`` path, or any `sim.recording.RecordingTarget`).

    Returns:
        What was written: ``"markdown"``, ``"json"``, ``"plot:<axis>"`` and ``"recording"``
        (the ``.rrd`` saved, if any).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    plots = {}
    for axis in results.axes:
        path = plot_axis(axis, plot_path(out, axis.name), detectors=results.detectors)
        written[f"plot:{axis.name}"] = path
        plots[axis.name] = path.name
    written["markdown"] = write_markdown(
        out / MARKDOWN_NAME, to_markdown(results, command=command, plots=plots)
    )
    written["json"] = write_json(out / JSON_NAME, results.to_json(command=command), indent=1)
    if save is not None:
        saved = record(results, save)
        if saved is not None:
            written["recording"] = saved
    return written


def record(results: StressResults, target: RecordingTarget | str | Path) -> Path | None:
    """The curves as a Rerun recording sent to ``target`` (a ``.rrd`` path or a
    `sim.recording.RecordingTarget`); the ``.rrd`` saved, if any."""
    from sim.recording import default_blueprint, open_recording  # Rerun: only to record

    target = RecordingTarget.coerce(target)
    blueprint = default_blueprint(
        scene=False, scores=False, events=False, stress=recording_names(results)
    )
    with open_recording(target, name="stress", seed=results.seed, blueprint=blueprint) as rec:
        log_results(rec, results)
    return target.save

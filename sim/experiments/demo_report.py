"""The demo's report: Markdown with tables and plots (``report.md``) and every number as JSON
(``results.json``), written from the run's :class:`sim.experiments.demo.DemoResult`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from reform import __version__
from sim.experiments.demo import CLASSIFIER_TEXT, SAVED_CLASSIFIER, DemoResult
from sim.experiments.demo_files import REPORT, RESULTS
from sim.experiments.hri import PAPER_HRI
from sim.experiments.report_files import write_json, write_markdown
from sim.experiments.sim2real import RECOMMENDED, recipe
from sim.experiments.tables import command_block, markdown_table, percent

SAVED_TEXT = CLASSIFIER_TEXT[SAVED_CLASSIFIER]  # the saved model's classifier, in words

__all__ = ["to_json", "to_markdown", "write_report"]

_STAGE_TEXT = {
    "scenarios": "simulate every registered scenario",
    "synthetic": "generate the synthetic training set",
    "training": "train REFORM",
    "evaluation": "score REFORM and GCFF",
    "stress": "stress tests (small grid)",
    "hri": "HRI re-enactment",
    "report": "recordings, figures, report",
    "total": "total",
}


def _rel(result: DemoResult, path: Any) -> str:
    try:
        return str(Path(path).relative_to(result.out_dir))
    except ValueError:
        return str(path)


def to_markdown(result: DemoResult) -> str:
    """The report page: what ran, the scenarios, the training set, the scores, the stress
    curves, the HRI re-enactment and where every file is."""
    budget = result.budget
    recorded = bool(result.recordings)
    lines = ["# reform-sim demo", ""]
    lines += command_block(result.command)
    lines += [
        f"Budget `{budget.name}`, seed {result.seed}, real datasets: "
        + (", ".join(result.datasets) if result.datasets else "none found")
        + f". Machine: {result.machine['cores']} cores, {result.machine['platform']}.",
        "",
        "## What ran",
        "",
        *markdown_table(
            ["stage", "seconds"],
            [[_STAGE_TEXT.get(k, k), f"{v:.1f}"] for k, v in result.timings.items()],
        ),
        "## Scenarios",
        "",
        "Every registered scenario, simulated briefly in MuJoCo (ground truth), with the groups "
        f"REFORM ({SAVED_TEXT}, trained on the synthetic set below) and GCFF (the paper's "
        "setting) find. F1 at T = 2/3 over the episode's annotated frames (`-`: no "
        "F-formation to find and none found scores no frame)."
        + (" Open a recording with `rerun <file>`." if recorded else ""),
        "",
    ]
    rows = [
        [
            f"`{s['scenario']}`",
            s["description"],
            str(s["people"]),
            f"{s['seconds']:g}",
            f"{s['fformations_per_frame']:.2f}",
            percent(s["reform_f1"]),
            percent(s["gcff_f1"]),
            f"[{s['recording']}]({s['recording']})" if s["recording"] else "-",
        ]
        for s in result.scenarios
    ]
    lines += markdown_table(
        [
            "scenario",
            "what it is",
            "agents",
            "seconds",
            "groups / frame",
            "REFORM F1",
            "GCFF F1",
            "recording",
        ],
        rows,
    )
    for s in result.scenarios:
        lines += [f"![{s['scenario']}]({s['figure']})", ""]
    lines += ["## Synthetic training set", ""]
    training = result.training
    lines += [
        *markdown_table(
            ["source", "episodes", "frames kept", "pairs kept"],
            [
                [
                    f"`{src.name}`",
                    str(src.episodes),
                    f"{training[src.name]['frames']:,}",
                    f"{training[src.name]['pairs']:,}",
                ]
                for src in budget.train
            ],
        ),
        "Hive-partitioned Parquet under `synthetic/train` (read it with "
        "`reform.datasets.read_parquet`); held-back episodes, from another master seed, under "
        "`synthetic/held-back`. The sources are balanced by pairs "
        "(`sim.experiments.synthetic.balance_pairs`).",
        "",
    ]
    lines += [
        f"The recipe `sim.experiments.sim2real` recommends: `{RECOMMENDED.recipe}` "
        f"({recipe(RECOMMENDED.recipe).text}), at this smaller budget.",
        "",
    ]
    lines += [
        f"Model: [`{_rel(result, result.model)}`]({_rel(result, result.model)}) (REFORM "
        f"{SAVED_TEXT}, skops; load it with `reform.persistence.load_model`).",
        "",
        "## Scores",
        "",
        "Protocol: GCFF's `ff_evalgroups` (`reform.evaluate`): singletons dropped, P and R "
        "means of the per-frame values, F1 of the means; %. SALSA test split: "
        "`reform.time_split` (per session, the last 40 % of annotated frames by time).",
        "",
    ]
    evaluations = result.evaluations
    rows = []
    for dataset, count in result.tests.items():
        for detector in result.detectors:
            s = evaluations.get((detector, dataset))
            if s is None:
                continue
            rows.append(
                [
                    detector,
                    f"{dataset} ({count})",
                    percent(s["pairwise_accuracy"]),
                    percent(s["precision"]),
                    percent(s["recall"]),
                    percent(s["f1"]),
                    percent(s["f1_t1"]),
                ]
            )
    lines += [
        *markdown_table(
            ["detector", "test set (frames)", "pair acc.", "P@2/3", "R@2/3", "F1@2/3", "F1@1"], rows
        ),
        "![F1 at T = 2/3](figures/scores.png)",
        "",
        "The full sim-to-real experiment (more data, tuned hyper-parameters, GCFF tuned, "
        "bootstrap intervals) is `reform-sim experiment sim2real`; its results are in "
        "`docs/results/sim2real.md`.",
        "",
        "## Stress tests (small grid)",
        "",
        "F1 of the demo's REFORM models and GCFF as tracking gets worse and crowds change, "
        "scored on held-out `mingle` parties (`sim.experiments.stress.run_stress`). Full tables: "
        "[`stress/stress.md`](stress/stress.md)"
        + ("; curves also in `recordings/stress.rrd`." if recorded else "."),
        "",
    ]
    stress = result.stress
    rows = []
    for axis in stress.axes:
        for detector in (SAVED_CLASSIFIER, "gcff"):
            curve = axis.curve(detector)[0]
            rows.append(
                [
                    axis.title,
                    f"REFORM {SAVED_TEXT}" if detector == SAVED_CLASSIFIER else "GCFF",
                    " / ".join(percent(v) for v in curve),
                    " / ".join(p.label for p in axis.points),
                ]
            )
    lines += markdown_table(["axis", "detector", "F1@2/3 at each level", "levels"], rows)
    for axis, plot in result.stress_plots.items():
        lines += [f"![{axis}]({plot})", ""]
    hri = result.hri
    lines += [
        "## The paper's HRI experiment, re-enacted",
        "",
        "The three proof-of-concept scenes with the Directions Robot (two people and the robot "
        "converse; two people converse, the robot left out; people walk past), "
        f"{hri.seeds} episode(s) each. Full page: [`hri.md`](hri.md)"
        + (
            "; recordings of each scene from the robot's view under `recordings/hri/`."
            if recorded
            else "."
        ),
        "",
    ]
    rows = []
    for view in hri.views:
        for key in hri.detectors:
            row = hri.row(key, view)
            s = row.scores["2/3"]
            rows.append(
                [
                    row.label,
                    view,
                    percent(s.precision.value),
                    percent(s.recall.value),
                    percent(s.f1.value),
                ]
            )

    for name, (p, r, f1) in PAPER_HRI.items():
        rows.append([f"paper: {name}", "Kinect", f"{p:.1f}", f"{r:.1f}", f"{f1:.1f}"])
    lines += [
        *markdown_table(["detector", "view", "P@2/3", "R@2/3", "F1@2/3"], rows),
        "## Files",
        "",
        f"Everything is under `{result.out_dir}`:",
        "",
    ]
    lines += [f"- `{_rel(result, p)}`" for p in result.recordings]
    lines += [
        f"- `{_rel(result, result.model)}`: the REFORM model",
        "- `results.json`: every number above",
        "- `figures/`, `stress/`: the plots",
        "",
    ]
    return "\n".join(lines)


def to_json(result: DemoResult) -> dict[str, Any]:
    """Every number of the demo, JSON-ready."""
    return {
        "kind": "reform-sim/demo",
        "schema_version": 1,
        "reform_version": __version__,
        "command": result.command,
        "budget": result.budget.name,
        "seed": result.seed,
        "datasets": list(result.datasets),
        "timings_s": {k: round(v, 2) for k, v in result.timings.items()},
        "scenarios": list(result.scenarios),
        "training": {k: dict(v) for k, v in result.training.items()},
        "recommended": RECOMMENDED.to_json(),
        "tests": dict(result.tests),
        "scores": [dict(v) for v in result.scores.values()],
        "stress": result.stress.to_json(command=result.command),
        "hri": result.hri.to_json(command=result.command),
        "files": {
            "report": REPORT,
            "model": _rel(result, result.model),
            "recordings": [_rel(result, p) for p in result.recordings],
            "figures": [_rel(result, p) for p in result.figures],
        },
    }


def write_report(result: DemoResult) -> dict[str, Path]:
    """Writes ``report.md`` and ``results.json`` into the demo's folder (atomically).

    Returns:
        What was written: ``"markdown"`` and ``"json"``.
    """
    return {
        "markdown": write_markdown(result.out_dir / REPORT, to_markdown(result)),
        "json": write_json(result.out_dir / RESULTS, to_json(result), indent=1),
    }

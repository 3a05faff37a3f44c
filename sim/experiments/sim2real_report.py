"""The sim-to-real experiment's report: Markdown tables and plots of a :class:`SimToReal`.

Three figures beside ``NAME.md``: ``NAME.png`` (F1 per real dataset, with intervals),
``NAME-rank.png`` (each detector's F1 in simulation against its mean on the real datasets) and
``NAME-calibration.png`` (Tightness and Symmetry by group size and the pair features, the
recommended recipe's synthetic data against each real dataset).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from sim.experiments.figures import WIDTH_IN, Bar, pyplot, save_png, score_bars
from sim.experiments.sim2real import (
    SALSA_TRAIN_SET,
    SIM_FIELD,
    SIM_PARTY,
    TAU_GOAL,
    SimToReal,
)
from sim.experiments.tables import command_block, markdown_table, percent

__all__ = ["calibration_figure", "rank_figure", "sim2real_figure", "to_markdown"]

MAIN_ROLES = ("recommended", "salsa-trained", "gcff-one", "gcff-own", "leave-one-out")


def _main_rows(result: SimToReal) -> tuple[str, ...]:
    return result.detectors(*MAIN_ROLES)


def sim2real_figure(result: SimToReal, path: str | os.PathLike[str]) -> Path:
    """F1 at T = 2/3 with 95 % intervals: one group per real dataset, one bar per main row."""
    groups: dict[str, list[Bar]] = {}
    for dataset in result.datasets:
        bars = []
        for detector in _main_rows(result):
            try:
                score = result.score(detector, dataset)
            except KeyError:
                continue
            low, high = score.f1_interval
            bars.append(Bar(_short(result, detector), 100 * score.f1, 100 * low, 100 * high))
        groups[dataset] = bars
    return score_bars(
        groups,
        path,
        ylabel="F1 at T = 2/3 (%)",
        title="Trained once on simulation, scored on real data",
    )


def _share(share: float) -> str:
    """A share in %: whole points, or below 1 % as such rather than rounded to 0."""
    return "< 1 %" if 0.0 < share < 0.005 else f"{100 * share:.0f} %"


def _short(result: SimToReal, detector: str) -> str:
    if detector == result.recommended.label:
        return f"recommended: {detector}"
    return detector


def rank_figure(result: SimToReal, path: str | os.PathLike[str]) -> Path:
    """Each ranked detector's F1 in simulation against its mean on the real data: one panel per
    simulated benchmark (the default party, the simulated field, the party as the field's
    datasets would record it)."""
    plt = pyplot()
    ranks = (result.rank, result.rank_field, result.rank_recorded)
    fig, axes = plt.subplots(1, len(ranks), figsize=(WIDTH_IN * 1.6, 4.5), sharey=True)
    for ax, rank in zip(axes, ranks, strict=True):
        x = 100 * np.asarray(rank.simulated)
        y = 100 * np.asarray(rank.real)
        colours = [_colour(result, d) for d in rank.detectors]
        ax.scatter(x, y, c=colours, s=18)
        for name, a, b in zip(rank.detectors, x, y, strict=True):
            if not name.startswith("REFORM") or name == result.recommended.label:
                ax.annotate(name, (a, b), fontsize=6, xytext=(3, 2), textcoords="offset points")
        ax.set_xlabel(f"F1 at T = 2/3 (%), {rank.benchmark}", fontsize=7)
        low, high = rank.interval
        ax.set_title(f"tau {rank.tau:.2f} (95% interval {low:.2f} to {high:.2f})", fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("mean F1 at T = 2/3 over the real datasets (%)")
    fig.suptitle("Does simulation rank the detectors as the real datasets do?")
    fig.tight_layout()
    return save_png(fig, path)


def _colour(result: SimToReal, detector: str) -> str:
    if detector == result.recommended.label:
        return "tab:red"
    if detector.startswith("GCFF"):
        return "tab:green"
    if "trained on SALSA" in detector:
        return "tab:orange"
    return "tab:blue"


def calibration_figure(result: SimToReal, path: str | os.PathLike[str]) -> Path:
    """Tightness and Symmetry by group size, and the in-group pair features' distributions, of
    the recommended recipe's synthetic data and of each real dataset."""
    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(WIDTH_IN, 6.5))
    colours = plt.get_cmap("tab10")
    for k, (name, stats) in enumerate(result.calibration.items()):
        style = {"color": colours(k % 10), "label": name}
        if name.startswith("synthetic"):
            style.update(linewidth=2.5, color="black")
        for ax, key, label in (
            (axes[0, 0], "tightness_m", "mean Tightness (m)"),
            (axes[0, 1], "symmetry", "mean Symmetry (deg)"),
        ):
            sizes = sorted(int(s) for s in stats[key] if stats["groups_by_size"][s] >= 5)
            ax.plot(sizes, [stats[key][str(s)] for s in sizes], marker="o", **style)
            ax.set_xlabel("group size")
            ax.set_ylabel(label)
        for ax, key, unit in (
            (axes[1, 0], "distance_shares", "edges_m"),
            (axes[1, 1], "effort_angle_shares", "edges_rad"),
        ):
            edges = np.asarray(stats[key][unit])
            centres = (edges[:-1] + edges[1:]) / 2
            ax.plot(centres, stats[key]["in_group"], **style)
        axes[1, 0].set_xlabel("Distance of in-group pairs (m)")
        axes[1, 1].set_xlabel("Effort Angle of in-group pairs (rad)")
        for ax in axes[1]:
            ax.set_ylabel("share of pairs")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=6)
    fig.suptitle("Synthetic training data against each real dataset (sizes with 5 groups or more)")
    fig.tight_layout()
    return save_png(fig, path)


def _score_cells(result: SimToReal, detector: str, dataset: str) -> list[str]:
    try:
        s = result.score(detector, dataset)
    except KeyError:
        return ["-"] * 6
    p, r, f = s.at["2/3"]
    low, high = s.f1_interval
    return [
        percent(p),
        percent(r),
        f"**{percent(f)}**" if s.role == "recommended" else percent(f),
        f"{percent(low)}-{percent(high)}",
        percent(s.at["1"][2]),
        s.note or "",
    ]


def to_markdown(
    result: SimToReal,
    *,
    command: str,
    figures: Sequence[str] = (),
) -> str:
    """The results page."""
    rec = result.recommended
    lines = [
        "# Sim-to-real: one detector trained on simulation alone, scored on every real dataset",
        "",
        *command_block(command),
        "REFORM trained only on generated data, chosen among "
        f"{len(result.selection)} candidates (recipes of synthetic data x classifiers x REFORM's "
        "options) on SALSA's training split and simulated validation episodes only, and scored "
        f"on every real dataset found ({', '.join(result.datasets)}). Protocol: the field's "
        "(GCFF's `ff_evalgroups` as `reform.evaluate` implements it); figures in %; intervals: "
        "95 % block bootstrap (stretches of time resampled, then frames within them).",
        "",
        f"**Recommended: {rec.label}**, saved as `recommended.skops` beside these results. Use it "
        "with `reform-sim detect --model recommended.skops --data DATASET` or "
        '`reform.load_model("recommended.skops")`.',
        "",
    ]
    met = sum(g.met for g in result.goals)
    lines += [f"**Goals met: {met} of {len(result.goals)}.**", ""]
    lines += markdown_table(
        ["goal", "required", "met", "figures (F1 at T = 2/3, %)"],
        [[g.name, g.required, "yes" if g.met else "**no**", g.figures] for g in result.goals],
    )
    for name in figures:
        lines += [f"![{name}]({name})", ""]

    lines += ["## Mean over the real datasets", ""]
    rows = []
    for detector in result.detectors():
        mean = result.mean_f1(detector)
        mean1 = result.mean_f1(detector, "1")
        scored = sum(
            1 for s in result.scores if s.detector == detector and s.dataset in result.datasets
        )
        rows.append([detector, str(scored), percent(mean), percent(mean1)])
    lines += [
        *markdown_table(["detector", "datasets", "F1 @2/3", "F1 @1"], rows),
        "Candidates other than the recommended one are reported for the rank agreement; their "
        "scores on real data chose nothing.",
        "",
    ]

    for dataset in result.datasets:
        lines += [f"## {dataset} ({result.frames.get(dataset, 0):,} frames)", ""]
        rows = [[d, *_score_cells(result, d, dataset)] for d in _main_rows(result)]
        lines += markdown_table(
            ["detector", "P@2/3", "R@2/3", "F1@2/3", "95% interval", "F1@1", "note"], rows
        )

    lines += [
        "## How the recommended model was chosen",
        "",
        "Selection score: the mean of two means of a candidate's F1 (T = 2/3): over SALSA's "
        "training split as recorded and as the field's other datasets would record it "
        "(positions scaled by 0.6 and by 1.6, the spread of group radii between datasets; "
        "orientation coded in 4 directions, the coarsest coding among them), and over the "
        "simulated validation sources (episodes of another master seed, never trained on). No "
        "scored frame is seen by the choice.",
        "",
    ]
    if result.choice_stability:
        shares = sorted(result.choice_stability.items(), key=lambda item: -item[1])
        own = result.choice_stability.get(result.recommended.label, 0.0)
        lines += [
            "How sure the choice is: resampling the frames it sees (SALSA's training split by "
            "stretches of time, each validation source's episodes), the best selection score "
            "goes to "
            + "; ".join(f"{label} {_share(share)}" for label, share in shares[:5])
            + (f"; {len(shares) - 5} others the rest" if len(shares) > 5 else "")
            + f". The recommended candidate has it in {_share(own)} of the resamples.",
            "",
        ]
    names = list(result.selection[0]["validation_f1"]) if result.selection else []
    views = list(result.selection[0]["salsa_views_f1"])[1:] if result.selection else []
    rows = []
    for entry in result.selection:
        rows.append(
            [
                entry["label"] + (" **(chosen)**" if entry["chosen"] else ""),
                percent(entry["salsa_train_f1"]),
                *[percent(entry["salsa_views_f1"][v]) for v in views],
                *[percent(entry["validation_f1"][n]) for n in names],
                percent(entry["score"]),
            ]
        )
    lines += [
        *markdown_table(
            [
                "candidate",
                "SALSA train",
                *[v.replace("salsa (training split), ", "SALSA train, ") for v in views],
                *[n.replace("validation: ", "sim: ") for n in names],
                "score",
            ],
            rows,
        ),
        "Recipes:",
        "",
    ]
    for entry in result.recipes:
        pairs = result.training[entry.name]
        lines.append(
            f"- `{entry.name}`: {entry.text}; "
            + ", ".join(f"`{s.name}` x {s.episodes}" for s in entry.sources)
            + f" ({pairs['frames']:,} frames, {pairs['pairs']:,} pairs after balancing)."
        )
    lines.append("")

    lines += ["## Does simulation rank detectors as real data does?", ""]
    for rank, what in (
        (result.rank, "held-out `mingle` episodes with its defaults, the stress tests' party"),
        (result.rank_field, "the mean over the simulated validation sources of every recipe"),
        (
            result.rank_recorded,
            "the same party as recorded and rescaled by 0.6 and by 1.6 and with orientation "
            "coded in 4 directions, averaged",
        ),
    ):
        low, high = rank.interval
        lines += [
            f"- **{rank.benchmark}** ({what}): Kendall's tau **{rank.tau:.2f}** (95 % interval "
            f"{low:.2f} to {high:.2f}, every set's frames resampled at once) over "
            f"{len(rank.detectors)} detectors.",
        ]
    if result.rank_between_real:
        lines += [
            "",
            "For reference, how far the real datasets agree with each other: each one ranks the "
            "same detectors against the mean of the others with Kendall's tau "
            + "; ".join(
                f"{r.benchmark} **{r.tau:.2f}** ({r.interval[0]:.2f} to {r.interval[1]:.2f})"
                for r in result.rank_between_real
            )
            + ". A simulated benchmark that agrees with the real mean no better than the field's "
            "datasets agree among themselves is as good a predictor as another real dataset.",
        ]
    compared, train = result.rank_compared, result.rank_salsa_train
    halves = result.rank_salsa_halves
    lines += [
        "",
        f"Two more views. Over the {len(compared.detectors)} detectors the experiment compares "
        "(the recommended model, REFORM trained on SALSA's training split, GCFF with one "
        f"setting; no other candidate), the {SIM_PARTY} agrees with the real mean with "
        f"Kendall's tau **{compared.tau:.2f}** ({compared.interval[0]:.2f} to "
        f"{compared.interval[1]:.2f}). And real data that no ranked detector trained on, "
        f"{SALSA_TRAIN_SET} as recorded, ranks the {len(train.detectors)} detectors trained "
        f"elsewhere (every candidate, GCFF with one setting) against the real mean with tau "
        f"**{train.tau:.2f}** ({train.interval[0]:.2f} to {train.interval[1]:.2f}), and "
        f"against SALSA's test split, the rest of the same recording, with tau "
        f"**{halves.tau:.2f}** ({halves.interval[0]:.2f} to {halves.interval[1]:.2f}): two "
        f"parts of one recording agree {'at or above' if halves.tau >= TAU_GOAL else 'below'} "
        f"the goal's {TAU_GOAL:g} on these detectors' order.",
    ]
    lines.append("")
    lines += [
        *markdown_table(
            [
                "detector",
                f"F1 {SIM_PARTY}",
                f"F1 {SIM_FIELD}",
                "F1 party, recorded",
                "mean F1 real",
            ],
            [
                [d, percent(s), percent(f), percent(v), percent(r)]
                for d, s, f, v, r in zip(
                    result.rank.detectors,
                    result.rank.simulated,
                    result.rank_field.simulated,
                    result.rank_recorded.simulated,
                    result.rank.real,
                    strict=True,
                )
            ],
        ),
        "## Synthetic data beside each real dataset",
        "",
    ]
    rows = []
    for name, stats in result.calibration.items():
        q = stats["nearest_neighbour_m"]
        tight = stats["tightness_m"]
        sym = stats["symmetry"]
        shown = [s for s in ("3", "5", "7") if s in tight]
        rows.append(
            [
                name,
                " / ".join(f"{v:.2f}" for v in q),
                ", ".join(f"f{s} {tight[s]:.2f}" for s in shown) or "-",
                ", ".join(f"f{s} {sym[s]:.0f}" for s in shown) or "-",
            ]
        )
    lines += [
        *markdown_table(
            ["data", "nearest neighbour q10/q25/q50 (m)", "Tightness (m)", "Symmetry (deg)"], rows
        ),
        f"Seed {result.seed}; {result.seconds / 60:.1f} min.",
        "",
    ]
    return "\n".join(lines)

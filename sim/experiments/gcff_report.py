"""The GCFF comparison (:class:`sim.experiments.gcff.GcffComparison`) as a Markdown page
(``docs/results/gcff-comparison.md``)."""

from __future__ import annotations

from reform.gcff import MDL_M2, STRIDE_M
from sim.experiments.gcff import BABBLE, PAPER_SCORES, SALSA_TEST, GcffComparison
from sim.experiments.tables import command_block, format_comparison, markdown_table

__all__ = ["to_markdown"]


def to_markdown(comparison: GcffComparison, *, command: str | None = None) -> str:
    """The comparison as a Markdown page: command, tables per dataset, tuning, notes."""
    search = comparison.tuning
    lines = ["# GCFF beside REFORM: SALSA test split and Babble", ""]
    if command:
        lines += command_block(command)
    lines += [
        f"Protocol: GCFF's `ff_evalgroups` (singletons dropped; P and R are means of the "
        f"per-frame values; F1 of those means), as `reform.metrics.evaluate` implements it. "
        f"Split: `reform.time_split` with train fraction {comparison.train_fraction:g} — per SALSA "
        f"session, the first annotated frames by time train "
        f"({comparison.frames['salsa-train']} frames), the rest test "
        f"({comparison.frames['salsa-test']} frames). Babble "
        f"({comparison.frames['babble']} frames) is never trained on. Scores in %.",
        "",
        'GCFF settings. *Paper*: the REFORM paper\'s "stride = 0.7, MDL = 30000", read as '
        "stride 70 cm = 0.7 m and mdl 30,000 cm² = 3.0 m² (GCFF's published settings are "
        "centimetres; GCFF computes in centimetres, see `reform.gcff`). *Reference default*: "
        f"the original code's stride 70 cm, mdl 10,000 cm² ({STRIDE_M:g} m, {MDL_M2:g} m²). "
        f"*Tuned*: grid search on the SALSA training split, objective F1 at "
        f"T = {search.threshold}: stride {search.best_stride:g} m, mdl {search.best_mdl:g} m² "
        f"(training F1 {100 * search.best_f1:.1f}).",
        "",
    ]
    for dataset, title in ((SALSA_TEST, "SALSA test split"), (BABBLE, "Babble")):
        rows = [r for r in comparison.results if r["dataset"] == dataset]
        if not rows:
            continue
        lines += [f"## {title}", "", format_comparison(rows, style="markdown").rstrip(), ""]
        paper = PAPER_SCORES[dataset]
        lines += [
            "The paper's figures on this data (T = 2/3, P / R / F1): "
            + "; ".join(f"{name} {p:.1f} / {r:.1f} / {f:.1f}" for name, (p, r, f) in paper.items())
            + ".",
            "",
        ]
    summary = comparison.summary()
    if summary:
        lines += ["## Summary (F1 at T = 2/3)", ""] + [f"- {line}" for line in summary] + [""]
    lines += ["## Tuning grid (SALSA training split, F1 at T = 2/3, %)", ""]
    strides = sorted({float(s) for s in search.stride})
    mdls = sorted({float(m) for m in search.mdl})
    score = {
        (float(s), float(m)): float(f)
        for s, m, f in zip(search.stride, search.mdl, search.f1, strict=True)
    }
    table = [
        [f"{s:g}"] + [f"{100 * score[(s, m)]:.1f}" if (s, m) in score else "-" for m in mdls]
        for s in strides
    ]
    headers = ["stride (m) \\ mdl (m²)"] + [f"{m:g}" for m in mdls]
    lines += markdown_table(headers, table)
    notes = comparison.all_notes()
    if notes:
        lines += ["## Notes", ""] + [f"- {note}" for note in notes] + [""]
    return "\n".join(lines)

"""Tables of a characterisation and of calibration comparisons, as Markdown or plain text.

:func:`characterisation_summary` turns a :class:`reform.calibration.Characterisation` into a
JSON-ready dict: Tightness and Symmetry by group size, one-way ANOVA and Tukey's HSD by size,
pair-feature quantiles and, for SALSA and Babble, the paper's published numbers.
:func:`format_characterisation` and :func:`format_calibration` read those dicts (and
:meth:`reform.calibration.Comparison.to_json`), so tables can be rebuilt from a saved JSON file.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from typing import Any

from reform.calibration import (
    IN_GROUP,
    MEASURES,
    MIN_GROUPS,
    OUT_OF_GROUP,
    PAIR_FEATURES,
    PAIR_KINDS,
    SYMMETRY,
    TIGHTNESS,
    TIGHTNESS_TOLERANCE_M,
    UNITS,
    Characterisation,
    anova_by_size,
    eligible_sizes,
    paper_characterisation_for,
    tukey_by_size,
)
from sim.experiments.tables import STYLES, render_table

__all__ = ["characterisation_summary", "format_calibration", "format_characterisation"]

_MISSING = "-"
_WIDTH = 100  # characters per line of prose
_DIGITS = {TIGHTNESS: 3, SYMMETRY: 1}  # decimals printed per measure
_SIGNIFICANCE = ((0.001, "***"), (0.01, "**"), (0.05, "*"))  # p bound -> mark


def characterisation_summary(
    characterisation: Characterisation,
    *,
    min_groups: int = MIN_GROUPS,
    tukey: bool = True,
    paper_name: str | None = None,
) -> dict[str, Any]:
    """Everything the characterisation report prints about one dataset, JSON-ready.

    Args:
        characterisation: from :func:`reform.calibration.characterise_dataset`.
        min_groups: fewest F-formations a size needs to enter the ANOVA and Tukey's HSD.
        tukey: include Tukey's HSD.
        paper_name: whose published numbers to put beside ours; default the dataset's name
            (``"salsa"`` and ``"babble"`` have some).

    Returns:
        ``characterisation.to_json()`` plus ``"anova"`` and ``"tukey"`` (measure -> result, or
        None when fewer than two sizes have ``min_groups`` F-formations), ``"min_groups"`` and
        ``"paper"`` (the paper's numbers or None).
    """
    out = characterisation.to_json()
    out["min_groups"] = min_groups
    out["anova"] = {}
    out["tukey"] = {}
    for measure in MEASURES:
        testable = (
            len(eligible_sizes(characterisation, measure=measure, min_groups=min_groups)) >= 2
        )
        out["anova"][measure] = (
            anova_by_size(characterisation, measure=measure, min_groups=min_groups).to_json()
            if testable
            else None
        )
        if tukey:
            out["tukey"][measure] = (
                tukey_by_size(characterisation, measure=measure, min_groups=min_groups).to_json()
                if testable
                else None
            )
    paper = paper_characterisation_for(characterisation.name if paper_name is None else paper_name)
    out["paper"] = None if paper is None else paper.to_json()
    return out


# --------------------------------------------------------------------------------------------
# Formatting helpers


def _check_style(style: str) -> None:
    if style not in STYLES:
        raise ValueError(f"style must be one of {STYLES}, got {style!r}")


def _number(value: float | None, digits: int, *, signed: bool = False) -> str:
    if value is None:
        return _MISSING
    return f"{value:+.{digits}f}" if signed else f"{value:.{digits}f}"


def _count(value: int) -> str:
    return f"{value:,}"


def _p(value: float | None) -> str:
    if value is None:
        return _MISSING
    if value == 0.0:
        return "< 1e-300"
    return f"{value:.1e}" if value < 1e-3 else f"{value:.3f}"


def _marks(p: float | None, style: str) -> str:
    """Significance stars; escaped in Markdown, where a bare ``*`` may open emphasis."""
    if p is None:
        return ""
    for bound, mark in _SIGNIFICANCE:
        if p < bound:
            return mark.replace("*", "\\*") if style == "markdown" else mark
    return ""


def _legend(style: str) -> str:
    """``* p < .05, ** p < .01, *** p < .001`` (escaped in Markdown)."""
    return ", ".join(
        f"{_marks(bound / 2, style)} p < {f'{bound:g}'.lstrip('0')}"
        for bound, _ in reversed(_SIGNIFICANCE)
    )


def _sizes(sizes: list[int]) -> str:
    if sizes and sizes == list(range(sizes[0], sizes[-1] + 1)):
        return f"{sizes[0]}-{sizes[-1]}" if len(sizes) > 1 else str(sizes[0])
    return ",".join(str(s) for s in sizes)


def _wrap(text: str) -> str:
    return textwrap.fill(text, width=_WIDTH, break_on_hyphens=False)


def _heading(text: str, level: int, style: str) -> str:
    if style == "markdown":
        return "#" * level + " " + text
    return text + "\n" + ("=" if level <= 2 else "-") * len(text)


def _paper_anova(paper: Mapping[str, Any] | None, measure: str) -> str:
    entry = None if paper is None else paper.get(f"{measure}_anova")
    if entry is None:
        return _MISSING
    return (
        f"F({entry['df_between']}, {entry['df_within']}) = {entry['F']:g}, p < {entry['p_below']:g}"
    )


# --------------------------------------------------------------------------------------------
# One dataset


def _versus_paper(
    ours: float, theirs: float | None, *, digits: int, paper_digits: int
) -> list[str]:
    """The paper's figure and ours minus it (missing where the paper gives none)."""
    difference = None if theirs is None else ours - theirs
    return [_number(theirs, paper_digits), _number(difference, digits, signed=True)]


# The measures of the by-size table: heading, key in the summary (``{key}_mean_{unit}``,
# ``{key}_std_{unit}``; the paper's ``{key}_{unit}``), unit, digits shown, the paper's digits.
_BY_SIZE_MEASURES = (
    ("Tightness (m)", "tightness", "m", 3, 2),
    ("Symmetry (deg)", "symmetry", "deg", 1, 0),
)


def _by_size_table(summary: Mapping[str, Any], style: str) -> str:
    paper = summary.get("paper")
    headers = ["size", "groups"]
    for heading, *_ in _BY_SIZE_MEASURES:
        headers += [heading, "sd"]
        if paper:
            headers += ["paper", "ours - paper"]
    rows = []
    for entry in summary["by_size"]:
        size = entry["size"]
        row = [str(size), _count(entry["count"])]
        for _, key, unit, digits, paper_digits in _BY_SIZE_MEASURES:
            mean = entry[f"{key}_mean_{unit}"]
            row += [_number(mean, digits), _number(entry[f"{key}_std_{unit}"], digits)]
            if paper:
                row += _versus_paper(
                    mean,
                    paper[f"{key}_{unit}"].get(str(size)),
                    digits=digits,
                    paper_digits=paper_digits,
                )
        rows.append(row)
    return render_table(headers, rows, style=style)


def _anova_table(summary: Mapping[str, Any], style: str) -> str:
    paper = summary.get("paper")
    headers = ["measure", "sizes", "F", "df", "p"] + (["paper"] if paper else [])
    rows = []
    for measure in MEASURES:
        entry = summary["anova"].get(measure)
        if entry is None:
            row = [measure, f"fewer than 2 with >= {summary['min_groups']} groups", *[_MISSING] * 3]
        else:
            row = [
                measure,
                _sizes(entry["sizes"]),
                _number(entry["F"], 2),
                f"{entry['df_between']}, {entry['df_within']}",
                _p(entry["p"]),
            ]
        if paper:
            row.append(_paper_anova(paper, measure))
        rows.append(row)
    return render_table(headers, rows, style=style)


def _tukey_table(entry: Mapping[str, Any], style: str) -> str:
    sizes = entry["sizes"]
    digits = _DIGITS[entry["measure"]]
    cells = {(p["size_a"], p["size_b"]): p for p in entry["pairs"]}
    headers = ["size", *(str(s) for s in sizes[:-1])]
    rows = []
    for b in sizes[1:]:
        row = [str(b)]
        for a in sizes[:-1]:
            pair = cells.get((a, b))
            row.append(
                ""
                if pair is None
                else _number(pair["difference"], digits, signed=True) + _marks(pair["p"], style)
            )
        rows.append(row)
    return render_table(headers, rows, style=style)


def _pair_table(summary: Mapping[str, Any], style: str) -> str:
    headers = ["feature", "pairs", "n", "mean", "q10", "q25", "median", "q75", "q90"]
    rows = []
    for feature in PAIR_FEATURES:
        for kind in PAIR_KINDS:
            entry = summary["pair_features"][feature][kind]
            rows.append(
                [
                    f"{feature} ({UNITS[feature]})",
                    kind,
                    _count(entry["n"]),
                    *(_number(entry[k], 3) for k in ("mean", "q10", "q25", "median", "q75", "q90")),
                ]
            )
    return render_table(headers, rows, style=style)


def format_characterisation(
    summary: Mapping[str, Any],
    *,
    style: str = "text",
    level: int = 2,
    sequences: Mapping[str, Mapping[str, Any]] | None = None,
) -> str:
    """The report of one dataset: by size (beside the paper), ANOVA, Tukey's HSD, pair features.

    Args:
        summary: :func:`characterisation_summary` output (or the same from a saved JSON file).
        style: ``"text"`` or ``"markdown"``.
        level: Markdown heading level of the dataset's title.
        sequences: optional per-sequence summaries, printed as by-size tables and ANOVAs.
    """
    _check_style(style)
    title = (
        f"{summary['name'] or 'dataset'}: {_count(summary['annotated_frames'])} annotated frames, "
        f"{_count(summary['fformations'])} F-formations, {_count(summary['pairs'])} pairs"
    )
    parts = [_heading(title, level, style), ""]
    paper = summary.get("paper")
    note = (
        "Tightness: mean distance of the members to the group's centre. Symmetry: sum over the "
        "N angular gaps between adjacent members (seen from the centre) of |360/N - gap|; 0 for "
        "pairs. sd: sample standard deviation over the F-formations of that size."
    )
    if paper:
        note += f" paper: {paper['provenance']} ({paper['frames']})."
    parts += [_wrap(note), "", _by_size_table(summary, style), ""]
    parts += [
        _wrap(
            f"One-way ANOVA with group size as the factor (sizes with >= {summary['min_groups']} "
            "F-formations; Symmetry from size 3, as it is 0 by definition for pairs):"
        ),
        "",
        _anova_table(summary, style),
        "",
    ]
    for measure in MEASURES:
        entry = (summary.get("tukey") or {}).get(measure)
        if entry is None:
            continue
        parts += [
            _wrap(
                f"Tukey's HSD, {measure}: mean of the row size minus mean of the column size "
                f"({UNITS[measure]}); {_legend(style)}."
            ),
            "",
            _tukey_table(entry, style),
            "",
        ]
    parts += [
        _wrap(
            "Pair features over every pair of the annotated frames (Distance in metres, Effort "
            f"Angle in radians); {IN_GROUP}: both in the same F-formation, {OUT_OF_GROUP}: any "
            "other pair."
        ),
        "",
        _pair_table(summary, style),
        "",
    ]
    for name, entry in (sequences or {}).items():
        heading = (
            f"{entry['name'] or name}: {_count(entry['annotated_frames'])} annotated frames, "
            f"{_count(entry['fformations'])} F-formations"
        )
        parts += [
            _heading(heading, level + 1, style),
            "",
            _by_size_table(entry, style),
            "",
            _anova_table(entry, style),
            "",
        ]
    return "\n".join(parts)


# --------------------------------------------------------------------------------------------
# Candidate against reference


def format_calibration(
    comparison: Mapping[str, Any], *, style: str = "text", level: int = 2
) -> str:
    """A candidate beside a reference: Tightness and Symmetry by size, KS tests, the verdict.

    Args:
        comparison: :meth:`reform.calibration.Comparison.to_json` output.
        style: ``"text"`` or ``"markdown"``.
        level: Markdown heading level of the title.
    """
    _check_style(style)
    tol = comparison.get("tolerance_m", TIGHTNESS_TOLERANCE_M)
    verdict = "yes" if comparison["within_tolerance"] else "no"
    title = (
        f"{comparison['candidate'] or 'candidate'} against {comparison['reference'] or 'reference'}"
    )
    parts = [_heading(title, level, style), ""]
    parts += [
        _wrap(
            f"Mean Tightness within {tol:g} m of the reference for every size the reference "
            f"holds at least {comparison['min_groups']} times: {verdict}. Differences are "
            "candidate minus reference."
        ),
        "",
    ]
    headers = ["size", "groups", "ref. groups", "checked"]
    for measure in MEASURES:
        unit = UNITS[measure]
        headers += [f"{measure.capitalize()} ({unit})", "reference", "difference"]
    rows = []
    for entry in comparison["by_size"]:
        row = [
            str(entry["size"]),
            _count(entry["candidate_count"]),
            _count(entry["reference_count"]),
            "yes" if entry["checked"] else "no",
        ]
        for measure in MEASURES:
            unit, digits = UNITS[measure], _DIGITS[measure]
            row += [
                _number(entry[f"{measure}_candidate_{unit}"], digits),
                _number(entry[f"{measure}_reference_{unit}"], digits),
                _number(entry[f"{measure}_difference_{unit}"], digits, signed=True),
            ]
        rows.append(row)
    parts += [render_table(headers, rows, style=style), ""]
    parts += [
        _wrap(
            "Two-sample Kolmogorov-Smirnov tests of the pair features (D: largest gap between "
            "the two empirical distribution functions; 0 = identical samples):"
        ),
        "",
    ]
    ks_rows = [
        [
            f"{k['feature']} ({k['unit']})",
            k["kind"],
            _number(k["statistic"], 3),
            _p(k["p"]),
            _count(k["candidate_n"]),
            _count(k["reference_n"]),
            _number(k["candidate_median"], 3),
            _number(k["reference_median"], 3),
        ]
        for k in comparison["ks"]
    ]
    parts += [
        render_table(
            ["feature", "pairs", "D", "p", "n", "ref. n", "median", "ref. median"],
            ks_rows,
            style=style,
        ),
        "",
    ]
    if comparison["failures"]:
        parts += ["Outside the tolerance:", ""]
        parts += [f"- {reason}" for reason in comparison["failures"]]
        parts.append("")
    return "\n".join(parts)

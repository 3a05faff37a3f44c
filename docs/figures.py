"""Draws the figure of the field's words on the getting-started page (docs/images/f-formation.png).

    python docs/figures.py

Left: four people placed as the `mingle` scenario places a group (`scenarios.mingle.SALSA_RADIUS`,
members evenly round the circle facing its centre, `scenarios.formation`), a fifth alone; each
person's transactional segment, the o-space that `sim.envs.estimate_o_space` finds, and the
p-space the members stand in. Right: one true group of three and three detections, each scored by
`reform.evaluate` at T = 2/3 and T = 1.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Wedge  # noqa: E402

import reform  # noqa: E402
from scenarios.formation import facing_centre  # noqa: E402
from scenarios.mingle import SALSA_RADIUS  # noqa: E402
from sim.envs import estimate_o_space  # noqa: E402

IMAGE = Path(__file__).resolve().parent / "images" / "f-formation.png"
SEGMENT_M = 0.8  # metres, how far a drawn transactional segment reaches
SEGMENT_DEG = 30.0  # degrees either side of a person's facing
BODY_M = 0.2  # metres, radius of a drawn person
MEMBER_COLOUR = "#1f77b4"
ALONE_COLOUR = "#7f7f7f"
# The right panel: a true group of three (ids 1, 2, 3) among five people, and three detections.
TRUE_GROUP = (1, 2, 3)
DETECTIONS = (
    ("{1, 2} and {3}", ((1, 2), (3,), (4,), (5,))),
    ("{1, 2, 3, 4}", ((1, 2, 3, 4), (5,))),
    ("{1, 2, 3, 4, 5}", ((1, 2, 3, 4, 5),)),
)


def _people(n: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """(n + 1, 2) places and (n + 1,) yaws: ``n`` members round an o-space, one person alone."""
    radius = SALSA_RADIUS(n)
    angles = math.pi / 4 + 2 * math.pi * np.arange(n) / n
    members = radius * np.column_stack([np.cos(angles), np.sin(angles)])
    places = np.vstack([members, [2.6, -0.4]])
    yaws = np.append(facing_centre(members, np.zeros(2)), math.radians(150.0))
    return places, yaws


def _formation(ax: plt.Axes) -> None:
    places, yaws = _people()
    members = slice(0, len(places) - 1)
    o_space = estimate_o_space(places[members], yaws[members])
    ax.add_patch(
        Circle(o_space.centre, o_space.radius + BODY_M, color="#dddddd", zorder=0, label="p-space")
    )
    ax.add_patch(
        Circle(
            o_space.centre,
            o_space.radius - BODY_M,
            facecolor="#ffe27a",
            edgecolor="#b8860b",
            linestyle="--",
            alpha=0.55,
            zorder=2.5,
            label="o-space",
        )
    )
    for k, (place, yaw) in enumerate(zip(places, yaws, strict=True)):
        alone = k == len(places) - 1
        colour = ALONE_COLOUR if alone else MEMBER_COLOUR
        facing = math.degrees(yaw)
        ax.add_patch(
            Wedge(
                place,
                SEGMENT_M,
                facing - SEGMENT_DEG,
                facing + SEGMENT_DEG,
                color=colour,
                alpha=0.3,
                zorder=2,
                label="transactional segment" if k == 0 else None,
            )
        )
        ax.add_patch(Circle(place, BODY_M, color=colour, zorder=3))
        ax.annotate(
            "",
            xy=place + 0.45 * np.array([math.cos(yaw), math.sin(yaw)]),
            xytext=place,
            arrowprops={"arrowstyle": "->", "color": "black", "lw": 1.2},
            zorder=4,
        )
    ax.annotate("o-space", o_space.centre, ha="center", va="center", fontsize=9)
    ax.annotate("alone", places[-1] + [0.0, -0.45], ha="center", fontsize=9, color=ALONE_COLOUR)
    ax.set_title("An F-formation of four, and one person alone")
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_xlim(-1.3, 3.3)
    ax.set_ylim(-1.3, 1.6)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def _scores() -> list[tuple[str, str, str]]:
    """(detection, matched at T = 2/3, matched at T = 1) as `reform.evaluate` scores them."""
    frame = reform.Frame(
        ids=np.arange(1, 6),
        position=np.zeros((5, 2)),
        yaw=np.zeros(5),
        groups=(TRUE_GROUP, (4,), (5,)),
    )
    rows = []
    for label, partition in DETECTIONS:
        scores = reform.evaluate([frame], [partition])
        matched = [("yes" if scores.at(t).recall == 1.0 else "no") for t in ("2/3", "1")]
        rows.append((label, *matched))
    return rows


def _threshold(ax: plt.Axes) -> None:
    ax.axis("off")
    ax.set_title("The T = 2/3 rule: true group {1, 2, 3}")
    scored = zip(_scores(), _shares(), strict=True)
    rows = [(label, share, t23, t1) for (label, t23, t1), share in scored]
    table = ax.table(
        cellText=rows,
        colLabels=("detected", "|G∩D| / max(|G|, |D|)", "T = 2/3", "T = 1"),
        loc="center",
        cellLoc="center",
    )
    table.auto_set_font_size(False)
    table.set_fontsize(9)
    table.auto_set_column_width(range(4))
    table.scale(1.0, 1.8)
    ax.text(
        0.5,
        0.12,
        "A detected group D matches the true group G when |G∩D| / max(|G|, |D|) ≥ T\n"
        "(scored here by reform.evaluate). T = 1 asks for the exact group.",
        ha="center",
        va="center",
        fontsize=9,
        transform=ax.transAxes,
    )


def _shares() -> list[str]:
    """The matching share of the detection that holds the most of the true group."""
    out = []
    truth = set(TRUE_GROUP)
    for _, partition in DETECTIONS:
        best = max(partition, key=lambda group: len(truth & set(group)))
        out.append(f"{len(truth & set(best))}/{max(len(truth), len(best))}")
    return out


def draw(path: Path = IMAGE) -> Path:
    """Draws the figure into ``path`` (PNG)."""
    figure, (left, right) = plt.subplots(
        1, 2, figsize=(11.0, 4.8), gridspec_kw={"width_ratios": [1.1, 1.0]}
    )
    _formation(left)
    _threshold(right)
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


if __name__ == "__main__":
    print(draw(Path(sys.argv[1]) if len(sys.argv) > 1 else IMAGE))

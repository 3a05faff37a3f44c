"""Crowd shapes, simulated against real: Symmetry, Tightness and nearest-neighbour distances.

For every real dataset of the field (SALSA's training split, Babble, the GCFF datasets
CoffeeBreak and Synth) and for ``mingle`` with its crowd options, one table row per group size:
the number of F-formations, their mean Tightness (metres) and mean Symmetry (degrees), both by
`reform.calibration.characterise_dataset`; and per dataset the 10% quantile and the median of
every person's nearest-neighbour distance (metres, annotated frames).

Print the table with::

    REFORM_SIM_DATASETS=/work/shared/datasets python -m sim.experiments.crowd_shapes

(``--seeds``, ``--duration`` set the simulated episodes; ``--real-only`` or ``--sim-only``
print part of it.)
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from reform.calibration import Characterisation, characterise_dataset
from reform.datasets import load_dataset
from reform.frame import Frame
from reform.splits import time_split

__all__ = [
    "REAL_DATASETS",
    "SALSA_SHAPES",
    "SIMULATED",
    "CrowdShapes",
    "crowd_shapes",
    "nearest_neighbour",
    "real_shapes",
    "simulated_shapes",
]

SIZES = tuple(range(2, 9))  # group sizes tabled
RATE_HZ = 0.5  # frames per second of a simulated episode measured
# name -> folder under the datasets root; SALSA measured on its training split only.
REAL_DATASETS: Mapping[str, str] = {
    "SALSA (train)": "salsa",
    "Babble": "babble",
    "CoffeeBreak": "coffeebreak",
    "Synth": "synth",
}
# mingle's crowd options whose groups come closest to SALSA's training split in the table
# (docs/guide/crowds.md): its nearest-neighbour q10 as near as the bodies allow, Symmetry of sizes
# 3-6 within 20 degrees, Tightness of sizes 2-8 within 0.1 m.
SALSA_SHAPES: Mapping[str, float] = MappingProxyType({"spacing": 0.46, "unevenness": 0.75})
# row label -> (scenario, options): mingle's default and its crowd options, mingle-randomised
SIMULATED: Mapping[str, tuple[str, Mapping[str, Any]]] = {
    "mingle (default)": ("mingle", {}),
    "mingle spacing=0.46": ("mingle", {"spacing": 0.46}),
    "mingle spacing=0.46 unevenness=0.75": ("mingle", dict(SALSA_SHAPES)),
    "mingle spacing=0.46 unevenness=1": ("mingle", {"spacing": 0.46, "unevenness": 1.0}),
    "mingle spacing=0.46 arrangements=0.5": ("mingle", {"spacing": 0.46, "arrangements": 0.5}),
    "mingle spacing=0.46 furniture=3": ("mingle", {"spacing": 0.46, "furniture": 3}),
    "mingle-randomised": ("mingle-randomised", {}),
}


def nearest_neighbour(frames: Iterable[Frame]) -> np.ndarray:
    """Every person's distance to the nearest other person, frame by frame, over the annotated
    frames with two or more people: (n,) metres."""
    out = []
    for frame in frames:
        if frame.groups is None or len(frame.ids) < 2:
            continue
        p = np.asarray(frame.position, dtype=np.float64)
        d = np.hypot(*(p[:, None, :] - p[None, :, :]).transpose(2, 0, 1))
        np.fill_diagonal(d, np.inf)
        out.append(d.min(axis=1))
    return np.concatenate(out) if out else np.zeros(0)


@dataclass(frozen=True)
class CrowdShapes:
    """One dataset's shapes.

    Attributes:
        name: the row's label.
        characterisation: Tightness and Symmetry by size.
        nn: (n,) nearest-neighbour distances, metres.
    """

    name: str
    characterisation: Characterisation
    nn: np.ndarray

    def nn_quantile(self, q: float) -> float:
        return float(np.quantile(self.nn, q)) if self.nn.size else float("nan")


def crowd_shapes(frames: Sequence[Frame], name: str) -> CrowdShapes:
    """The shapes of ``frames``, labelled ``name``."""
    return CrowdShapes(name, characterise_dataset(frames, name=name), nearest_neighbour(frames))


def real_shapes(root: str | Path) -> list[CrowdShapes]:
    """The shapes of each of `REAL_DATASETS` under ``root`` (SALSA: its training split)."""
    out = []
    for label, folder in REAL_DATASETS.items():
        frames: Sequence[Frame] = tuple(load_dataset(Path(root) / folder))
        if folder == "salsa":
            frames = time_split(frames)[0]
        out.append(crowd_shapes(frames, label))
    return out


def simulated_shapes(
    scenario: str,
    options: Mapping[str, Any],
    *,
    label: str,
    seeds: int = 6,
    duration: float = 300.0,
) -> CrowdShapes:
    """The shapes of ``seeds`` episodes (seeds 0 ..) of ``scenario`` with ``options``, each
    ``duration`` seconds, measured every 2 s."""
    from sim.episode import simulate_episode  # the simulator only where simulated rows are asked

    frames: list[Frame] = []
    for seed in range(seeds):
        episode = simulate_episode(
            scenario, seed=seed, rate=RATE_HZ, options={"duration": duration, **options}
        )
        frames.extend(episode.dataset)
    return crowd_shapes(frames, label)


def table(rows: Sequence[CrowdShapes]) -> str:
    """A Markdown table: per row the nearest-neighbour q10 / median and, per size 2-8, the
    mean Tightness (m) / Symmetry (deg) and the count of F-formations."""
    head = ["data", "NN q10 m", "NN median m"] + [f"size {s}: T m / S deg (n)" for s in SIZES]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        cells = [row.name, f"{row.nn_quantile(0.1):.2f}", f"{row.nn_quantile(0.5):.2f}"]
        by_size = row.characterisation.by_size()
        for s in SIZES:
            stats = by_size.get(s)
            if stats is None:
                cells.append("-")
            else:
                cells.append(
                    f"{stats.tightness_mean:.2f} / {stats.symmetry_mean:.0f} ({stats.count})"
                )
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m sim.experiments.crowd_shapes")
    parser.add_argument("--seeds", type=int, default=6, help="episodes per simulated row")
    parser.add_argument("--duration", type=float, default=300.0, help="seconds per episode")
    parser.add_argument("--real-only", action="store_true", help="only the real datasets")
    parser.add_argument("--sim-only", action="store_true", help="only the simulated rows")
    args = parser.parse_args(argv)
    rows = []
    if not args.sim_only:
        root = os.environ.get("REFORM_SIM_DATASETS")
        if not root:
            parser.exit(2, "crowd_shapes: set REFORM_SIM_DATASETS to the datasets' folder\n")
        rows += real_shapes(root)
    if not args.real_only:
        for label, (scenario, options) in SIMULATED.items():
            rows.append(
                simulated_shapes(
                    scenario, options, label=label, seeds=args.seeds, duration=args.duration
                )
            )
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Chooses the open constants of the field's detectors on SALSA's training split alone.

For each of ``proximity``, ``dominant-sets``, ``gtcg``, ``hvff`` and ``hvff-multiscale``, every
setting of the catalogue options that declare a ``grid`` (the constants their papers leave open;
all other options at their defaults) is run on the annotated frames of SALSA's training part
(`reform.time_split` at 0.6, the part `reform-sim train --frames train` uses; every
``--every``-th frame) and scored by F1 at T = 2/3 (`reform.evaluate`). No scored set takes part:
not SALSA's test part, nor Babble, CoffeeBreak or Synth. Prints, per detector, the setting with
the best training F1 (ties: the first in grid order), that F1 and the runner-ups, as Markdown.

Run: ``python benchmarks/choose_field_defaults.py [--every 4] [--datasets DIR] [--quick]``
(a few minutes on two cores; ``--quick`` scores every 120th frame, a smoke run whose choices mean
little). The catalogue's defaults (`reform/catalogue.py`) are the choices of a full run.
"""

from __future__ import annotations

import itertools
import time
from typing import Any

from timing import BenchmarkParser, datasets_folder

from reform import evaluate, make_detector, time_split
from reform.datasets import load_dataset
from reform.detectors import detector_options

# The field's non-deep detectors whose open constants this script chooses (a curated set).
FIELD_DETECTORS = ("proximity", "dominant-sets", "gtcg", "hvff", "hvff-multiscale")
TRAIN_FRACTION = 0.6  # SALSA's training share, as `reform-sim train --frames train`
OBJECTIVE = "2/3"  # the threshold T whose F1 is maximised
RUNNER_UPS = 3  # settings shown after the chosen one


def grid_of(name: str) -> tuple[tuple[str, ...], list[tuple[Any, ...]]]:
    """The names of ``name``'s options that declare a grid, and every setting of them (the
    product of their grids, in declaration order)."""
    options = [option for option in detector_options(name) if option.grid]
    names = tuple(option.name for option in options)
    return names, list(itertools.product(*(option.grid for option in options)))


def training_f1(name: str, setting: dict[str, Any], frames: tuple) -> float:
    """F1 at :data:`OBJECTIVE` of detector ``name`` with ``setting`` on ``frames``."""
    detector = make_detector(name, **setting).fit(frames)
    return evaluate(frames, detector.predict(frames), thresholds=(OBJECTIVE,)).at(OBJECTIVE).f1


def _shown(names: tuple[str, ...], values: tuple[Any, ...]) -> str:
    return ", ".join(f"{n}={v:g}" for n, v in zip(names, values, strict=True))


def main() -> int:
    parser = BenchmarkParser(__doc__)
    parser.add_datasets_argument()
    parser.add_sized("--every", default=4, quick=120, help="score every K-th training frame")
    args = parser.parse_args()

    folder = datasets_folder(args.datasets, "salsa")
    dataset = load_dataset(folder / "salsa")
    train, _ = time_split(dataset.frames, TRAIN_FRACTION)
    annotated = tuple(frame for frame in train if frame.groups is not None)
    frames = annotated[:: args.every]
    print(
        f"SALSA training split ({TRAIN_FRACTION:g} of each sequence's annotated frames): "
        f"{len(annotated)} frames, every {args.every}th scored: {len(frames)} frames; "
        f"objective F1 at T = {OBJECTIVE}"
    )
    print()
    print(f"| detector | chosen | training F1 (T = {OBJECTIVE}) | runner-ups (F1) | settings |")
    print("|---|---|---:|---|---:|")
    for name in FIELD_DETECTORS:
        started = time.perf_counter()
        names, settings = grid_of(name)
        scored = [
            (training_f1(name, dict(zip(names, values, strict=True)), frames), index, values)
            for index, values in enumerate(settings)
        ]
        ranked = sorted(scored, key=lambda item: (-item[0], item[1]))
        best_f1, _, best = ranked[0]
        others = "; ".join(
            f"{_shown(names, values)} ({100 * f1:.1f})"
            for f1, _, values in ranked[1 : 1 + RUNNER_UPS]
        )
        print(
            f"| {name} | {_shown(names, best)} | {100 * best_f1:.1f} | {others} | "
            f"{len(settings)} |",
            flush=True,
        )
        elapsed = time.perf_counter() - started
        print(f"<!-- {name}: {len(settings)} settings in {elapsed:.1f} s -->", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

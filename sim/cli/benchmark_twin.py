"""What ``reform-sim benchmark --twin`` does: each detector's F1 predicted at a place, on its
venue twin, before any label exists (`sim.twins.predict`); with the place's recording
(``--data``, its groups never read), calibrated there by how much the detectors agree with one
another; with several twins of one place (fitted with different seeds), the mean of their
predictions (`sim.twins.predict.mean_prediction`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from sim.cli._common import CliError, check_output, refuse_given_twice, twin_data_name
from sim.progress import progress_bar
from sim.ticking import ticking

MARKDOWN = "benchmark-twin.md"
JSON = "benchmark-twin.json"
UNCALIBRATED = (
    "Not calibrated at the place: give its recording too, `--data RECORDING` (its groups are "
    "never read), and each prediction is calibrated there by how far the detectors agree with "
    "their consensus on it, which predicts the place more closely than the twin alone (the "
    "venue twins guide, Predictions)."
)


# What the benchmark of labelled datasets reads and a twin's does not: (flag, attribute, value
# when not given).
NOT_READ_WITH_TWIN = (
    ("--test-split", "test_split", None),
    ("--frames", "frames", None),
    ("--train-fraction", "train_fraction", None),
    ("--temporal", "temporal", False),
    ("--detector-timeout", "detector_timeout", None),
    ("--max-memory", "max_memory", None),
    ("--backend", "backend", "local"),
    ("--address", "address", None),
)


def refuse_unread(args: argparse.Namespace) -> None:
    """`CliError` for a flag ``benchmark`` would not read: one of `NOT_READ_WITH_TWIN` with
    --twin, or --twin-data without it (rather than a run that silently leaves it out)."""
    if args.twin is None:
        if args.twin_data is not None:
            raise CliError("--twin-data is the generated data of a --twin; give --twin TWIN.json")
        return
    for flag, name, unset in NOT_READ_WITH_TWIN:
        if getattr(args, name) != unset:
            raise CliError(
                f"{flag}: not read with --twin (it sets how labelled datasets are scored; a "
                "twin's benchmark predicts each detector's F1 on the twin's own data); leave it "
                "out, or leave out --twin"
            )


def _twins(args: argparse.Namespace) -> tuple[list[str], list[Any]]:
    """The --twin files and their twins, read and checked: one place, --twin-data with one
    twin only, at most one --data (the place's recording)."""
    from sim.twins import read_twin

    paths = [str(path) for path in args.twin]
    twins = [read_twin(path) for path in paths]  # a nonsense twin is one line, before any work
    if args.data and len(args.data) > 1:
        raise CliError(
            f"--data with --twin: expected the place's one recording, found {len(args.data)}"
        )
    if args.twin_data and len(paths) > 1:
        raise CliError(
            f"--twin-data: expected one --twin with it, found {len(paths)} (each twin's data "
            "are twin-data/ beside its file)"
        )
    for path, twin in zip(paths[1:], twins[1:], strict=True):
        if twin.name != twins[0].name:
            raise CliError(
                f"--twin {path}: expected twins of one place, found a twin of {twin.name!r} "
                f"beside one of {twins[0].name!r} ({paths[0]})"
            )
    refuse_given_twice("--twin", [(p, Path(p).resolve()) for p in paths], kind="twin file")
    seeds: dict[int, str] = {}  # a mean over twins is over different seeds
    for path, twin in zip(paths, twins, strict=True):
        if twin.seed in seeds:
            raise CliError(
                f"--twin {path}: field seed: expected twins fitted with different seeds, found "
                f"seed {twin.seed} in {path} and in {seeds[twin.seed]}"
            )
        seeds[twin.seed] = path
    return paths, twins


def _place(args: argparse.Namespace) -> list[Any] | None:
    """The place's recording (--data): the one its twins were fitted to, or another of the
    place; its frames calibrate the predictions, and `sim.twins.predict` removes their groups
    before it runs anything on them; None without --data."""
    if not args.data:
        return None
    from reform.datasets import load_dataset, resolve
    from reform.datasets.summary import repairs_line

    dataset = load_dataset(
        resolve(args.data[0]),
        units=args.units,
        metres_per_pixel=args.metres_per_pixel,
        time_unit=args.time_unit,
    )
    repaired = repairs_line(dataset, str(args.data[0]))
    if repaired:
        print(repaired, file=sys.stderr)
    return list(dataset)


def run_twin(args: argparse.Namespace) -> int:
    """``benchmark --twin``: --detector (catalogued names) and --model (REFORM files) narrow the
    candidates (default: every catalogued detector a twin can run, GCFF tuned on the twin and
    REFORM trained on it); --data, the place's recording, calibrates the predictions there."""
    from reform.detectors import detector_names
    from reform.persistence import load_model
    from sim.experiments.report_files import write_json, write_markdown
    from sim.generate import FolderRefused
    from sim.twins import twin_data
    from sim.twins.data import DATA_FOLDER
    from sim.twins.predict import (
        Candidate,
        catalogue_candidates,
        mean_prediction,
        predict,
        table,
    )

    paths, twins = _twins(args)
    check_output("--out", args.out, folder=True)
    place = _place(args)
    candidates = catalogue_candidates()
    if args.detector:
        unknown = [d for d in args.detector if d not in detector_names()]
        if unknown:
            raise CliError(
                f"--detector {unknown[0]}: expected a catalogued detector with --twin "
                f"({', '.join(detector_names())})"
            )
        wanted = set(args.detector)
        candidates = [c for c in candidates if c.name in wanted]
    models = [
        Candidate(f"reform ({Path(m).stem})", "reform", detector=load_model(m), votes=False)
        for m in args.model or ()
    ]
    candidates += models

    runs = []
    for path, twin in zip(paths, twins, strict=True):
        folder = Path(args.twin_data) if args.twin_data else Path(path).parent / DATA_FOLDER
        try:
            frames = list(twin_data(twin, folder, n_jobs=args.jobs or 1, progress=not args.quiet))
        except FolderRefused as exc:  # named as the command names it
            raise CliError(exc.message(twin_data_name(args))) from None
        desc = "benchmark --twin" if len(paths) == 1 else f"benchmark --twin {path}"
        bar = progress_bar(
            total=len(candidates), desc=desc, unit="detector", file=sys.stderr, disable=args.quiet
        )
        at_work: list[str] = []  # the detector being scored

        def progress(label: str, bar: Any = bar, at_work: list[str] = at_work) -> None:
            bar.update(len(at_work))  # called as each detector starts: the one before is done
            at_work[:] = [label]
            bar.set_postfix_str(label)

        # Redrawn while a detector works (gcff-tuned tunes itself first: seconds).
        with bar, ticking(bar):
            runs.append(
                predict(frames, candidates, place=place, seed=twin.seed, progress=progress)
            )
            bar.update(len(candidates) - bar.n)

    predictions = runs[0] if len(runs) == 1 else mean_prediction(runs)
    out = Path(args.out)
    kind = f"{twins[0].mode} twin" + ("s" if len(paths) > 1 else "")
    where = f"the place of {twins[0].name} ({kind}, {', '.join(paths)})"
    if args.data:
        where += f", its recording {args.data[0]}"
    text = table(predictions, place=where, twins=len(paths))
    if place is None:
        text += f"\n{UNCALIBRATED}\n"
    write_markdown(out / MARKDOWN, text)
    record: dict[str, Any] = {"twin": paths[0] if len(paths) == 1 else paths}
    record["place"] = args.data[0] if args.data else None
    record["predictions"] = [p.to_json() for p in predictions]
    if len(runs) > 1:
        record["each_twin"] = [[p.to_json() for p in run] for run in runs]
    write_json(out / JSON, record, indent=2)
    print(text, end="")
    print(f"wrote {out}/: {MARKDOWN}, {JSON}", file=sys.stderr)
    return 0

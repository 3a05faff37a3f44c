"""What ``reform-sim benchmark --twin`` does: each detector's F1 predicted at a place, on its
venue twin, before any label exists (`sim.twins.predict`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from sim.cli._common import CliError, check_output
from sim.progress import progress_bar
from sim.ticking import ticking

MARKDOWN = "benchmark-twin.md"
JSON = "benchmark-twin.json"


def run_twin(args: argparse.Namespace) -> int:
    """``benchmark --twin``: --detector (catalogued names) and --model (REFORM files) narrow the
    candidates (default: every catalogued detector a twin can run, GCFF tuned on the twin and
    REFORM trained on it); --data is refused (the twin stands for the data)."""
    from reform.detectors import detector_names
    from reform.persistence import load_model
    from sim.twins import read_twin, twin_data
    from sim.twins.data import DATA_FOLDER
    from sim.twins.predict import Candidate, catalogue_candidates, predict, table

    twin = read_twin(args.twin)  # a nonsense twin is one line, before any work
    if args.data:
        raise CliError("--twin predicts for the twin's place; it takes no --data")
    check_output("--out", args.out, folder=True)
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
        Candidate(f"reform ({Path(m).stem})", "reform", detector=load_model(m))
        for m in args.model or ()
    ]
    candidates += models
    folder = Path(args.twin_data) if args.twin_data else Path(args.twin).parent / DATA_FOLDER
    frames = list(twin_data(twin, folder, n_jobs=args.jobs or 1, progress=not args.quiet))

    bar = progress_bar(
        total=len(candidates),
        desc="benchmark --twin",
        unit="detector",
        file=sys.stderr,
        disable=args.quiet,
    )

    at_work: list[str] = []  # the detector being scored

    def progress(label: str) -> None:  # called as each detector starts: the one before is done
        bar.update(len(at_work))
        at_work[:] = [label]
        bar.set_postfix_str(label)

    # Redrawn while a detector works (gcff-tuned tunes itself first: seconds).
    with bar, ticking(bar):
        predictions = predict(frames, candidates, seed=twin.seed, progress=progress)
        bar.update(len(candidates) - bar.n)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    text = table(predictions, place=f"the place of {twin.name} ({twin.mode} twin, {args.twin})")
    (out / MARKDOWN).write_text(text)
    (out / JSON).write_text(
        json.dumps(
            {"twin": str(args.twin), "predictions": [p.to_json() for p in predictions]},
            indent=2,
        )
        + "\n"
    )
    print(text, end="")
    print(f"wrote {out}/: {MARKDOWN}, {JSON}", file=sys.stderr)
    return 0

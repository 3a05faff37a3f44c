"""What ``reform-sim evaluate`` does when it runs.

Its arguments are `sim.cli._evaluate`."""

from __future__ import annotations

import argparse
import json
import sys

from reform.atomic import atomic_open
from reform.metrics import evaluate
from sim.cli._common import CliError, check_output, check_recording, load_data
from sim.cli._detection import detect_frames, record_detection
from sim.cli._detectors import check_detector, detector_params
from sim.experiments.tables import format_report


def run(args: argparse.Namespace) -> int:
    spec = check_detector(args)
    check_output("--json", args.json)
    check_output("--markdown", args.markdown)
    check_recording(args)
    dataset = load_data(args)
    frames = dataset.annotated()
    if not frames:
        raise CliError(f"{args.data}: the dataset has no annotated frames, nothing to evaluate")
    detector, predictions = detect_frames(args, spec, frames)
    evaluation = evaluate(frames, predictions)
    result = evaluation.to_json(
        detector=args.detector,
        dataset=dataset.name,
        detector_params=detector_params(detector),
        source=dataset.source,
        per_frame=args.per_frame,
    )
    print(format_report(result, style="text"), end="")
    if args.json:
        with atomic_open(args.json) as handle:
            json.dump(result, handle, indent=2, allow_nan=False)
            handle.write("\n")
        print(f"wrote {args.json}", file=sys.stderr)
    if args.markdown:
        with atomic_open(args.markdown) as handle:
            handle.write(format_report(result, style="markdown"))
        print(f"wrote {args.markdown}", file=sys.stderr)
    record_detection(
        args,
        command="evaluate",
        dataset=dataset,
        frames=frames,
        predictions=predictions,
        evaluation=evaluation,
    )
    return 0

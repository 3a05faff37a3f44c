"""What ``reform-sim evaluate`` does when it runs.

Its arguments are `sim.cli._evaluate`."""

from __future__ import annotations

import argparse
import json
import sys

from reform.atomic import atomic_open
from reform.metrics import evaluate
from sim.cli._common import check_frames, check_recording, load_data, select_frames
from sim.cli._detection import detect_frames, record_detection
from sim.cli._detectors import check_detector, detector_params
from sim.cli._evaluate import BASENAME
from sim.cli._grammar import report_outputs
from sim.experiments.tables import format_report


def run(args: argparse.Namespace) -> int:
    spec = check_detector(args)
    check_frames(args)
    outputs = report_outputs(args, BASENAME)
    check_recording(args)
    dataset = load_data(args)
    frames = select_frames(args, dataset.frames, doing="evaluate on")
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
    if "json" in outputs:
        path = outputs["json"][1]
        with atomic_open(path) as handle:
            json.dump(result, handle, indent=2, allow_nan=False)
            handle.write("\n")
        print(f"wrote {path}", file=sys.stderr)
    if "markdown" in outputs:
        path = outputs["markdown"][1]
        with atomic_open(path) as handle:
            handle.write(format_report(result, style="markdown"))
        print(f"wrote {path}", file=sys.stderr)
    record_detection(
        args,
        command="evaluate",
        dataset=dataset,
        frames=frames,
        predictions=predictions,
        evaluation=evaluation,
    )
    return 0

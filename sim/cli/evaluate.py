"""What ``reform-sim evaluate`` does when it runs.

Its arguments are `sim.cli._evaluate`."""

from __future__ import annotations

import argparse

from reform.metrics import evaluate
from sim.cli._common import (
    check_frames,
    check_recording,
    frame_memory_limit,
    load_data,
    select_frames,
    temporal_tolerance,
)
from sim.cli._detection import detect_frames, record_detection
from sim.cli._detectors import check_detector, detector_params
from sim.cli._evaluate import BASENAME
from sim.cli._grammar import report_outputs, write_outputs
from sim.experiments.tables import format_report
from sim.recording import pandas_withheld


def run(args: argparse.Namespace) -> int:
    spec = check_detector(args)
    memory = frame_memory_limit(args)  # a malformed --max-memory is refused before any reading
    check_frames(args)
    outputs = report_outputs(args, BASENAME)
    check_recording(args)
    dataset = load_data(args)
    frames = select_frames(args, dataset.frames, doing="evaluate on")
    tolerance = temporal_tolerance(args, frames)
    detector, predictions = detect_frames(args, spec, frames, memory)
    evaluation = evaluate(frames, predictions)
    result = evaluation.to_json(
        detector=args.detector,
        dataset=dataset.name,
        detector_params=detector_params(detector),
        source=dataset.source,
        per_frame=args.per_frame,
    )
    if tolerance is not None:
        from reform.seeding import Role, derive_rng
        from reform.temporal import evaluate_events

        rng = derive_rng(0, Role.TEMPORAL_BOOTSTRAP)
        result["temporal"] = evaluate_events(
            frames, predictions, tolerance_s=tolerance, rng=rng
        ).to_json()
    print(format_report(result, style="text"), end="")
    write_outputs(
        outputs, document=result, markdown=lambda: format_report(result, style="markdown")
    )
    with pandas_withheld():  # pyarrow, under Rerun, would import it for nothing: see there
        record_detection(
            args,
            command="evaluate",
            dataset=dataset,
            frames=frames,
            predictions=predictions,
            evaluation=evaluation,
        )
    return 0

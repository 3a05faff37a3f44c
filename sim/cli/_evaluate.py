"""``reform-sim evaluate``: score a detector on a dataset's annotated frames, print the table."""

from __future__ import annotations

import argparse
import json
import sys

from sim.cli._common import CliError, check_output, check_recording, load_data
from sim.cli._detection import add_detection_arguments, detect_frames, record_detection
from sim.cli._detectors import check_detector, detector_params

_DESCRIPTION = """\
Runs a detector on every annotated frame of a dataset and scores it with the field's protocol
(GCFF's ff_evalgroups): pairwise accuracy; precision, recall and F1 at T = 2/3 and T = 1
(singletons dropped, means of the per-frame P and R, F1 of the means); micro-averaged P/R/F1;
recall and precision by group size. Prints the table; --json and --markdown save it.
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "evaluate",
        help="score a detector on a dataset (pairwise accuracy, P/R/F1 at T=2/3 and T=1)",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    from sim.recording import add_recording_arguments

    add_detection_arguments(parser)
    parser.add_argument(
        "--json", metavar="OUT", help="write the results as JSON (docs/json-schema.md)"
    )
    parser.add_argument("--markdown", metavar="OUT", help="write the table as Markdown")
    parser.add_argument(
        "--per-frame",
        action="store_true",
        help="include every frame's scores in the JSON (for time-series plots)",
    )
    add_recording_arguments(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from reform.atomic import atomic_open
    from reform.metrics import evaluate
    from sim.experiments.tables import format_report

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

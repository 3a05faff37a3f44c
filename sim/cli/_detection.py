"""What ``detect`` and ``evaluate`` share: a detector, the dataset it runs on, and the run's
Rerun recording."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from typing import Any

from sim.cli._common import add_data_arguments, add_max_memory_argument
from sim.cli._detectors import DetectorSpec, add_detector_arguments
from sim.cli._grammar import add_quiet, show_progress, ticking_bar


def add_detection_arguments(parser: argparse.ArgumentParser) -> None:
    """``--detector`` and every detector's options, the dataset (``--data`` ...),
    ``--max-memory``, ``--quiet``."""
    add_detector_arguments(parser)
    add_data_arguments(parser)
    add_max_memory_argument(
        parser,
        holds="a frame whose people would take the detector more is refused before any frame "
        "is predicted, naming how many people fit",
    )
    add_quiet(parser, old=())


def detect_frames(
    args: argparse.Namespace,
    spec: DetectorSpec,
    frames: Sequence[Any],
    memory: tuple[int, str],
) -> tuple[Any, list[Any]]:
    """The detector ``spec`` builds from the flags, and its partition of every frame, checked
    (`reform.detectors.run_detector`: a detector that raises or returns something that is not
    a partition of each frame's people is one line naming it and the frame). Frames too large
    for ``memory`` (the bytes one frame may take and how to name them,
    `sim.cli._common.frame_memory_limit`) are refused first
    (`reform.detectors.check_frame_memory`)."""
    from reform.detectors import check_frame_memory, run_detector

    limit, limit_text = memory

    started = time.perf_counter()
    # The bar moves while the detector is made (a model file read: seconds of imports) and
    # predicts every frame in one call.
    with ticking_bar(args, f"running {args.detector}", len(frames)):
        detector = spec.build(args)
        check_frame_memory(
            args.detector,
            detector,
            frames,
            limit=limit,
            limit_text=limit_text,
            source=getattr(args, "data", None) or "",
            hint="give a larger --max-memory, or fewer people a frame",
        )
        partitions = run_detector(
            args.detector,
            detector,
            frames,
            deadline_s=args.detector_timeout,
            source=getattr(args, "data", None) or "",
        )
    if show_progress(args):
        seconds = time.perf_counter() - started
        print(f"{args.detector}: {len(frames):,} frames in {seconds:.1f} s", file=sys.stderr)
    return detector, partitions


def record_detection(
    args: argparse.Namespace,
    *,
    command: str,
    dataset: Any,
    frames: Sequence[Any],
    predictions: Sequence[Any],
    evaluation: Any = None,
) -> None:
    """Records the run where the recording flags say (``--save`` ...); nothing without them.

    Args:
        args: the parsed command line.
        command: the subcommand, the first word of the run's name.
        dataset: the `reform.Dataset` the frames come from.
        frames, predictions: the frames the detector ran on and its partitions.
        evaluation: the `reform.metrics.Evaluation` of the predictions, if scored.
    """
    from sim.recording import target_from_args

    if target_from_args(args) is None:  # nothing to record: Rerun is not even imported
        return
    from sim.recording import record_from_args

    record_from_args(
        args,
        frames,
        {args.detector: predictions},
        None if evaluation is None else {args.detector: evaluation},
        name=f"{command}-{args.detector}-{dataset.name}",
        dataset=dataset.name,
    )

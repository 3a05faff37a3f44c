"""What ``detect`` and ``evaluate`` share: a detector, the dataset it runs on, and the run's
Rerun recording."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from sim.cli._common import add_data_arguments
from sim.cli._detectors import add_detector_arguments, build_detector


def add_detection_arguments(parser: argparse.ArgumentParser) -> None:
    """``--detector`` and every detector's options, then the dataset (``--data`` ...)."""
    add_detector_arguments(parser)
    add_data_arguments(parser)


def run_detector(args: argparse.Namespace, frames: Sequence[Any]) -> tuple[Any, list[Any]]:
    """The detector the flags name, and its partition of every frame."""
    detector = build_detector(args)
    return detector, detector.predict(frames)


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
    from sim.recording import record_from_args

    record_from_args(
        args,
        frames,
        {args.detector: predictions},
        None if evaluation is None else {args.detector: evaluation},
        name=f"{command}-{args.detector}-{dataset.name}",
        dataset=dataset.name,
    )

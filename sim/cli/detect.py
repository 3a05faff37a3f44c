"""What ``reform-sim detect`` does when it runs.

Its arguments are `sim.cli._detect`."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from reform import __version__
from reform.atomic import atomic_open
from sim.cli._common import (
    CliError,
    check_frames,
    check_output,
    check_recording,
    frame_memory_limit,
    load_data,
    select_frames,
)
from sim.cli._detection import detect_frames, record_detection
from sim.cli._detectors import check_detector, detector_params

# Version of the JSON written by ``detect`` (docs/json-schema.md).
DETECTIONS_SCHEMA_VERSION = 1


def detections_json(
    frames, predictions, *, detector: str, params: dict[str, Any], dataset, indices
) -> dict[str, Any]:
    """The ``detect`` output (docs/json-schema.md); groups sorted, singletons left out."""

    records = []
    for index, frame, partition in zip(indices, frames, predictions, strict=True):
        groups = sorted(sorted(int(m) for m in g) for g in partition if len(g) >= 2)
        records.append(
            {
                "index": int(index),
                "sequence": frame.sequence,
                "time": frame.time,
                "groups": groups,
            }
        )
    return {
        "schema_version": DETECTIONS_SCHEMA_VERSION,
        "kind": "reform-sim/detections",
        "reform_version": __version__,
        "detector": detector,
        "detector_params": params,
        "dataset": dataset.name,
        "source": dataset.source,
        "frames": records,
    }


def _dumps(result: dict[str, Any]) -> str:
    """JSON with the header indented and one line per frame record (readable, diff-friendly)."""
    header = {key: value for key, value in result.items() if key != "frames"}
    text = json.dumps(header, indent=2, allow_nan=False)
    records = ",\n".join("    " + json.dumps(r, allow_nan=False) for r in result["frames"])
    frames = '  "frames": [\n' + records + "\n  ]" if records else '  "frames": []'
    return text[: text.rindex("}")].rstrip() + ",\n" + frames + "\n}\n"


def run(args: argparse.Namespace) -> int:
    spec = check_detector(args)
    memory = frame_memory_limit(args)  # a malformed --max-memory is refused before any reading
    check_frames(args)
    check_output("--out", args.out)
    check_recording(args)
    dataset = load_data(args)
    if args.frames is None:
        indices = list(range(len(dataset.frames)))
    else:
        chosen = {id(f) for f in select_frames(args, dataset.frames, doing="run on")}
        indices = [i for i, f in enumerate(dataset.frames) if id(f) in chosen]
    frames = [dataset.frames[i] for i in indices]
    if not frames:
        raise CliError(f"{args.data}: no frames to run the detector on")
    detector, predictions = detect_frames(args, spec, frames, memory)
    result = detections_json(
        frames,
        predictions,
        detector=args.detector,
        params=detector_params(detector),
        dataset=dataset,
        indices=indices,
    )
    with atomic_open(args.out) as handle:
        handle.write(_dumps(result))
    n_groups = sum(len(record["groups"]) for record in result["frames"])
    print(
        f"{args.detector} on {dataset.name}: {len(frames):,} frames, {n_groups:,} F-formations "
        f"detected; wrote {args.out}",
        file=sys.stderr,
    )
    record_detection(
        args, command="detect", dataset=dataset, frames=frames, predictions=predictions
    )
    return 0

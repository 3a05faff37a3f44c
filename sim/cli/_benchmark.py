"""``reform-sim benchmark``: every detector on every dataset, one table as the field reports it."""

from __future__ import annotations

import argparse

from sim.cli._common import (
    add_backend_arguments,
    add_max_memory_argument,
    add_unit_arguments,
    run_with,
)
from sim.cli._detectors import add_detector_timeout
from sim.cli._grammar import add_frames, add_out, add_quiet, add_recordings

DEFAULT_OUT = "benchmark-output"
# Cells each worker process must have before `benchmark` starts workers by default (--jobs not
# given): a worker costs about a second of CPU to start and reads each dataset again, and a cell
# of the default detectors takes a fifth of a second (the default detectors on salsa, babble,
# coffeebreak and synth, 12 cells: 5.9 s in this process, 11 to 13 s with two workers).
CELLS_PER_WORKER = 16
DEFAULT_DETECTORS = (
    "gcff",
    "gcff-own",
    "majority",
)  # the field's reference rows; `all`: the catalogue

DESCRIPTION = """\
Runs every detector given on every dataset given (default: every dataset found, fetched with
`reform-sim datasets fetch` or in $REFORM_SIM_DATASETS, else ../shared/datasets) and scores
them with the field's protocol: per dataset precision, recall and F1 at T = 2/3 and T = 1, and
the mean over datasets, with the original papers' published figures beside ours where they
exist. Writes OUT/benchmark.md, OUT/benchmark.json, OUT/benchmark.png and one Rerun recording
per dataset (OUT/recordings/<dataset>.rrd: its scenes, the ground truth, every detector's
groups and mistakes). A dataset with no annotated frames in the part scored is refused before
any detector runs.

Detectors (--detector, repeatable): any name of the detector catalogue (`reform-sim evaluate
--help` lists them with their options), run with its declared defaults: gcff (GCFF with one
setting for every dataset, the REFORM paper's 0.7 m / 30,000 cm²), gcff-own (GCFF with each
dataset's own shipped settings_gc.mat, per sequence; datasets that ship none are skipped),
gcff-tuned (searched on the training part of each dataset's time split, scored on its test part
only), majority, ...; `all` for every catalogued detector that needs no model file; an
installed detector's name, or package.module:factory. REFORM models: --model FILE
(repeatable), written by `reform-sim train`. Default: gcff, gcff-own, majority, plus every
--model.

Honest evaluation: datasets named by --test-split (default: salsa) are scored on the test part
of reform.time_split only, the frames `reform-sim train --frames train` leaves out.

--temporal also scores every detector's group events in time on each dataset (a "Groups in
time" table: event recall and precision, latency, false events per minute, identity switches;
docs/guide/temporal.md), matched within 1 s or the dataset's frame interval where longer.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        action="append",
        metavar="PATH|NAME",
        help="a dataset (repeatable): a path, or a fetched or local dataset's name "
        "(default: every dataset found)",
    )
    add_unit_arguments(parser, whose="the --data datasets'")
    parser.add_argument(
        "--detector",
        action="append",
        metavar="SPEC",
        help="a detector (repeatable): a catalogue name (gcff, gcff-own, gcff-tuned, majority, "
        "...), all (every catalogued detector that needs no model file), a plugin's name or "
        f"package.module:factory (default: {', '.join(DEFAULT_DETECTORS)})",
    )
    parser.add_argument(
        "--model",
        action="append",
        metavar="FILE",
        help="a model file written by `reform-sim train` (repeatable): REFORM's .skops, or "
        "DANTE's .safetensors (train --detector dante)",
    )
    parser.add_argument(
        "--test-split",
        action="append",
        metavar="NAME",
        help="score this dataset on its test split only (repeatable; default: salsa)",
    )
    add_frames(
        parser,
        default=None,
        scored="scored in every dataset",
        default_help="the test part in --test-split datasets, all elsewhere",
    )
    parser.add_argument(
        "--twin",
        action="append",
        metavar="TWIN.json",
        help="predict each detector's F1 at the place a venue twin (`reform-sim twin`) describes, "
        "on the twin's data, before any label exists (writes OUT/benchmark-twin.md and .json); "
        "repeatable: twins of one place fitted with different --seed, each detector's "
        "prediction their mean, each twin's beside it; with --data, the place's recording "
        "(its groups never read), each prediction calibrated there by the detectors' "
        "agreement with their consensus",
    )
    parser.add_argument(
        "--twin-data",
        metavar="DIR",
        help="with one --twin: its generated dataset (default: twin-data/ beside twin.json)",
    )
    add_out(
        parser,
        folder=True,
        default=DEFAULT_OUT,
        help="folder for benchmark.md, benchmark.json, benchmark.png and recordings/",
    )
    parser.add_argument(
        "--temporal",
        action="store_true",
        help="also score each detector's group events in time (docs/guide/temporal.md)",
    )
    add_detector_timeout(parser)
    add_max_memory_argument(
        parser,
        holds="a dataset frame whose people would take a detector more (divided among the "
        "workers) is refused before any cell runs, naming how many people fit",
    )
    add_recordings(parser, default=True, each="dataset")
    add_backend_arguments(
        parser,
        jobs_help=f"worker processes (when not given, one per {CELLS_PER_WORKER} cells at most: "
        "fewer cells run in this process)",
    )
    add_quiet(parser)
    parser.set_defaults(handler=run_with("sim.cli.benchmark:_run"))

"""``reform-sim stress``: REFORM and GCFF under tracking errors, crowds and the robot's sensor."""

from __future__ import annotations

import argparse
import dataclasses
import shlex
import sys

from sim.cli._common import CliError, check_output, check_recording
from sim.cli._detectors import detector_name, make_plugin

_DESCRIPTION = """\
F1 at T = 2/3 and T = 1 of REFORM (weighted KNN, bagged trees, logistic regression) and GCFF as
functions of position noise, orientation noise, tracking dropout, crowd density, number and size
of groups, and the sensor (ground truth against the robot's head sensor with occlusion), with
95% bootstrap intervals over several test episodes per point. The detectors are trained once on
a synthetic training set (mingle and word-improv episodes whose seeds differ from the test
episodes'); no real data is needed. Writes DIR/stress.md (tables and plots), DIR/stress.json and
DIR/stress-<axis>.png, and with --save a Rerun recording of the curves.

Grids: 'default' (the documented run, a few minutes on two cores) and 'small' (seconds).

--detector NAME|package.module:factory (repeatable) runs detectors of your own beside these: a
name of the detector registry (majority, an installed package's entry point in the group
reform_sim.detectors) or a plugin's path. One with fit() is fitted on the same training frames.
Their scores are in stress.json.
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "stress",
        help="stress tests: F1 of REFORM and GCFF against noise, dropouts, crowds, the sensor",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    from sim.experiments.stress_grid import AXES, GRIDS

    parser.add_argument(
        "--grid",
        choices=tuple(GRIDS),
        default="default",
        help="levels and sizes (default: default)",
    )
    parser.add_argument(
        "--seeds",
        type=int,
        default=None,
        metavar="K",
        help="test episodes per point (default: the grid's, 5 for default, 2 for small)",
    )
    parser.add_argument("--seed", type=int, default=0, help="master seed (default 0)")
    parser.add_argument(
        "--axes",
        default=None,
        metavar="A,B,...",
        help=f"axes to run (default all): {','.join(AXES)}",
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=None,
        metavar="N",
        help="worker processes (default: every core); results do not depend on it",
    )
    parser.add_argument(
        "--detector",
        action="append",
        dest="detectors",
        type=detector_name,
        default=None,
        metavar="NAME|module:factory",
        help="also run this detector (repeatable): a registered name such as majority, an "
        "installed package's (entry-point group reform_sim.detectors), or package.module:factory "
        "(the current folder is searched too); fitted on the training frames when it has fit()",
    )
    parser.add_argument(
        "--out",
        default="stress",
        metavar="DIR",
        help="folder for stress.md, stress.json and the plots (default: ./stress)",
    )
    parser.add_argument(
        "--save",
        default=None,
        metavar="PATH.rrd",
        help="also save the curves as a Rerun recording; open it with `rerun PATH.rrd`",
    )
    parser.set_defaults(handler=run)


def _command(args: argparse.Namespace) -> str:
    words = ["reform-sim", "stress", "--grid", args.grid]
    if args.seeds is not None:
        words += ["--seeds", str(args.seeds)]
    if args.seed != 0:
        words += ["--seed", str(args.seed)]
    if args.axes is not None:
        words += ["--axes", args.axes]
    if args.jobs is not None:
        words += ["--jobs", str(args.jobs)]
    for name in args.detectors or ():
        words += ["--detector", name]
    words += ["--out", args.out]
    if args.save is not None:
        words += ["--save", args.save]
    return shlex.join(words)


def run(args: argparse.Namespace) -> int:
    from sim.experiments.stress import AXES, DETECTOR_LABELS, GRIDS, run_stress
    from sim.experiments.stress_report import write_report

    grid = GRIDS[args.grid]
    if args.seeds is not None:
        if args.seeds < 1:
            raise CliError(f"--seeds must be >= 1, got {args.seeds}")
        grid = dataclasses.replace(grid, seeds=args.seeds)
    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    axes = None
    if args.axes is not None:
        axes = [a.strip() for a in args.axes.split(",") if a.strip()]
        unknown = [a for a in axes if a not in AXES]
        if unknown or not axes:
            raise CliError(f"--axes must name axes among {','.join(AXES)}, got {args.axes!r}")
    check_output("--out", args.out, folder=True)
    check_recording(args)
    plugins = {}
    for name in args.detectors or ():
        if name in DETECTOR_LABELS:
            raise CliError(
                f"--detector {name}: stress always runs {DETECTOR_LABELS[name]} (trained on its "
                "synthetic training set); --detector adds detectors of your own"
            )
        if name in plugins:
            raise CliError(f"--detector {name} is given twice")
        plugins[name] = make_plugin(name)

    def progress(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    results = run_stress(
        grid, seed=args.seed, jobs=args.jobs, axes=axes, plugins=plugins, progress=progress
    )
    if results.grid_name == "custom":
        results = dataclasses.replace(results, grid_name=f"{args.grid} (--seeds {args.seeds})")
    written = write_report(results, args.out, command=_command(args), save=args.save)
    print(
        f"stress tests done in {results.timings['total']:.0f} s "
        f"({results.environment.get('cpu_s', 0):.0f} CPU s on {results.jobs} worker(s))",
        file=sys.stderr,
    )
    for key, path in written.items():
        print(f"wrote {key}: {path}")
    return 0

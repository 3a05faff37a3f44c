"""``reform-sim stress``: REFORM and GCFF under tracking errors, crowds and the robot's sensor."""

from __future__ import annotations

import argparse

from sim.cli._common import (
    add_backend_arguments,
    add_dry_run_argument,
    add_max_memory_argument,
)
from sim.cli._detectors import add_detector_timeout, detector_name
from sim.cli._grammar import add_episodes, add_out, add_quiet, add_seed, run_loading
from sim.experiments.stress_grid import AXES, GRIDS
from sim.recording import add_recording_arguments

DESCRIPTION = """\
F1 at T = 2/3 and T = 1 of REFORM (weighted KNN, bagged trees, logistic regression) and GCFF as
functions of position noise, orientation noise, tracking dropout, crowd density, number and size
of groups, the sensor (ground truth against the robot's head sensor with occlusion), scripted
changes and the size of a crowd (a concourse of up to 1,000 people), with
95% bootstrap intervals over several test episodes per point. The detectors are trained once on
a synthetic training set (mingle and word-improv episodes whose seeds differ from the test
episodes'); no real data is needed. Writes DIR/stress.md (tables and plots), DIR/stress.json and
DIR/stress-<axis>.png, and with --save a Rerun recording of the curves.

Grids: 'default' (the documented run, a few minutes on two cores) and 'small' (seconds).

--detector NAME|package.module:factory (repeatable) runs more detectors beside these: a name of
the detector catalogue (majority, gcff with its one stated setting, proximity, ...; `all` for
every catalogued detector that needs no model file and no dataset of its own), an installed
package's entry point in the group reform_sim.detectors, or a plugin's path. One with fit() is
fitted on the same training frames. Their scores are in stress.json.

--temporal also scores every detector's group events in time at every point (event recall and
precision, latency, false events per minute, identity switches, pooled over the point's
episodes; docs/guide/temporal.md), in stress.json and a "Groups in time" table in stress.md.
"""


def _detector_or_all(text: str) -> str:
    """``--detector``'s type: ``all``, a catalogue name or a plugin's path."""
    return text if text == "all" else detector_name(text)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--grid",
        choices=tuple(GRIDS),
        default="default",
        help="levels and sizes (default: default)",
    )
    add_episodes(
        parser,
        help="test episodes per point (default: the grid's, 5 for default, 2 for small)",
        old="--seeds",
    )
    add_seed(parser)
    parser.add_argument(
        "--axes",
        default=None,
        metavar="A,B,...",
        help=f"axes to run (default all): {','.join(AXES)}",
    )
    add_backend_arguments(parser)
    parser.add_argument(
        "--detector",
        action="append",
        dest="detectors",
        type=_detector_or_all,
        default=None,
        metavar="NAME|module:factory",
        help="also run this detector (repeatable): a catalogue name such as majority, all (every "
        "catalogued detector that needs no model file), an installed package's (entry-point "
        "group reform_sim.detectors), or package.module:factory (the current folder is searched "
        "too); fitted on the training frames when it has fit()",
    )
    add_detector_timeout(parser)
    add_out(
        parser,
        folder=True,
        default="stress",
        help="folder for stress.md, stress.json and the plots",
    )
    parser.add_argument(
        "--temporal",
        action="store_true",
        help="also score each detector's group events in time (docs/guide/temporal.md)",
    )
    add_recording_arguments(parser, what="the curves")
    add_max_memory_argument(
        parser, holds="the stress test holds its test episodes and their scores"
    )
    add_dry_run_argument(parser)
    add_quiet(parser, old=())
    parser.set_defaults(handler=run_loading("sim.cli.stress:run", "MuJoCo and scikit-learn"))

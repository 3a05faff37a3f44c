"""``reform-sim policy evaluate``: the scripted joining baseline's success rate over seeded
episodes of a Gymnasium environment."""

from __future__ import annotations

import argparse

from sim.cli._common import Action, add_actions
from sim.cli._grammar import add_episodes, add_quiet, add_seed, rename, run_loading, setter

DESCRIPTION = """\
Runs the scripted baseline of the joining task (go to the gap in the detected o-space, face the
centre; sim.envs.JoinPolicy) for --episodes episodes of a joining environment (episode k is
reset with seed S + k) and prints its success rate. The environment detects F-formations with
GCFF, with the REFORM model given by --model, or, with --detector truth, knows them (the
policy's upper bound).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_actions(parser, ACTIONS)


def _evaluate_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--env", required=True, metavar="ID", help="environment id, e.g. ReformSim/Mingle-v0"
    )
    add_episodes(parser, default=100, help="episodes (default 100)")
    add_seed(parser, help="episode k uses seed S + k")
    parser.add_argument(
        "--model", default=None, metavar="FILE.skops", help="REFORM model file to detect with"
    )
    parser.add_argument(
        "--detector",
        default=None,
        metavar="NAME",
        help="detector without a --model: a name of the detector catalogue that needs nothing "
        "more (gcff, the default; `reform-sim evaluate --help` lists them), a plugin's "
        "package.module:factory, or truth (the ground truth of what the robot sees: the "
        "policy's upper bound)",
    )
    parser.add_argument(
        "--out",
        default=None,
        metavar="FILE.json",
        help="write the results as JSON here (default: printed only)",
    )
    rename(parser, "--json", "--out", setter("out"), metavar="FILE")
    add_quiet(parser, old=())
    rename(parser, "--progress", "(progress is shown by default)", setter("quiet", False), nargs=0)
    parser.set_defaults(handler=run_loading("sim.cli.policy:_evaluate", "Gymnasium and MuJoCo"))


ACTIONS = (
    Action(
        "evaluate",
        "success rate of the scripted baseline over seeded episodes",
        DESCRIPTION,
        _evaluate_arguments,
    ),
)

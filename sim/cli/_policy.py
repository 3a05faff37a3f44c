"""``reform-sim policy evaluate``: the scripted joining baseline's success rate over seeded
episodes of a Gymnasium environment."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from sim.cli._common import CliError, check_output

_DESCRIPTION = """\
Runs the scripted baseline of the joining task (go to the gap in the detected o-space, face the
centre; sim.envs.JoinPolicy) for --episodes episodes of a joining environment (episode k is
reset with seed S + k) and prints its success rate. The environment detects F-formations with
GCFF, with the REFORM model given by --model, or, with --detector truth, knows them (the
policy's upper bound).
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "policy",
        help="scripted baseline of the Gymnasium joining task: success rate",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_actions,
    )


def _actions(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    actions.add_parser(
        "evaluate",
        help="success rate of the scripted baseline over seeded episodes",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_evaluate_arguments,
    )


def _evaluate_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--env", required=True, metavar="ID", help="environment id, e.g. ReformSim/Mingle-v0"
    )
    parser.add_argument("--episodes", type=int, default=100, metavar="N", help="default 100")
    parser.add_argument(
        "--seed", type=int, default=0, metavar="S", help="episode k uses seed S + k (default 0)"
    )
    parser.add_argument(
        "--model", default=None, metavar="FILE", help="REFORM model file to detect with"
    )
    parser.add_argument(
        "--detector",
        choices=("gcff", "truth"),
        default=None,
        help="detector without a --model: gcff (default) or truth (the ground truth of what the "
        "robot sees: the policy's upper bound)",
    )
    parser.add_argument("--json", default=None, metavar="FILE", help="write the results here")
    parser.add_argument("--progress", action="store_true", help="show a progress bar")
    parser.set_defaults(handler=_evaluate)


def _evaluate(args: argparse.Namespace) -> int:
    import gymnasium as gym

    import sim.envs
    from reform.atomic import atomic_open
    from sim.envs.policy import evaluate_policy

    if args.env not in gym.registry:
        known = ", ".join(i for i in sim.envs.ENV_IDS if not i.endswith("Observe-v0"))
        raise CliError(f"--env: unknown environment {args.env!r}; the joining ones: {known}")
    if args.episodes < 1:
        raise CliError(f"--episodes must be a positive number, got {args.episodes}")
    check_output("--json", args.json)
    kwargs = {}
    if args.detector is not None:
        if args.model is not None:
            raise CliError("give --model or --detector, not both")
        kwargs["detector"] = args.detector
    if args.model is not None:
        if not Path(args.model).is_file():
            raise CliError(f"--model: no such file {args.model}")
        kwargs["model"] = args.model
    result = evaluate_policy(
        args.env, episodes=args.episodes, seed=args.seed, progress=args.progress, **kwargs
    )
    steps = result.mean_steps_to_success
    print(
        f"{result.env_id}: success rate {result.success_rate:.1%} "
        f"({sum(e.success for e in result.episodes)}/{len(result.episodes)} episodes, seeds "
        f"{args.seed}-{args.seed + args.episodes - 1}, detector {result.detector}); mean return "
        f"{result.mean_return:.2f}; mean steps to join "
        + ("-" if steps is None else f"{steps:.0f}")
        + f"; {result.seconds:.0f} s"
    )
    if args.json is not None:
        with atomic_open(args.json, "w") as handle:
            json.dump(result.to_json(), handle, indent=2)
            handle.write("\n")
    return 0

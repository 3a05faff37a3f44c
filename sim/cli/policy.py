"""What ``reform-sim policy evaluate`` does when it runs.

Its arguments are `sim.cli._policy`."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import gymnasium as gym

import sim.envs
from reform.atomic import atomic_open
from sim.cli._common import CliError, check_output
from sim.envs.policy import evaluate_policy
from sim.sizing import check_episodes


def _evaluate(args: argparse.Namespace) -> int:
    joining = [i for i in sim.envs.ENV_IDS if not i.endswith("Observe-v0")]
    if args.env not in joining:
        what = "an environment of another task" if args.env in gym.registry else "unknown"
        raise CliError(
            f"--env {args.env}: expected one of the joining task's environments "
            f"({', '.join(joining)}), got {what}"
        )
    if args.episodes < 1:
        raise CliError(f"--episodes must be a positive number, got {args.episodes}")
    check_episodes(args.episodes, what="the policy evaluation", flag="--episodes")
    check_output("--out", args.out)
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
        args.env, episodes=args.episodes, seed=args.seed, progress=not args.quiet, **kwargs
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
    if args.out is not None:
        with atomic_open(args.out, "w") as handle:
            json.dump(result.to_json(), handle, indent=2)
            handle.write("\n")
    return 0

"""The ``reform-sim`` command: thin subcommands that parse, call one library function, report."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from sim.cli import (
    _calibrate,
    _characterize,
    _data,
    _demo,
    _detect,
    _evaluate,
    _experiment,
    _experiment_gcff,
    _experiment_hri,
    _experiment_sim2real,
    _generate,
    _policy,
    _scenarios,
    _simulate,
    _stress,
    _train,
)
from sim.cli._common import CliError

# Each module exposes ``register(subparsers)``, adding its subcommand(s) with a ``handler``.
_COMMANDS = (
    _demo,
    _data,
    _evaluate,
    _detect,
    _experiment_gcff,
    _experiment,
    _experiment_hri,
    _experiment_sim2real,
    _train,
    _characterize,
    _scenarios,
    _simulate,
    _generate,
    _calibrate,
    _stress,
    _policy,
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="reform-sim",
        description=(
            "Simulate social scenes, detect F-formations (REFORM, GCFF), evaluate, log to Rerun."
        ),
    )
    from reform import __version__

    parser.add_argument("--version", action="version", version=f"reform-sim {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in _COMMANDS:
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except (CliError, ValueError, FileNotFoundError, KeyError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"reform-sim {args.command}: error: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

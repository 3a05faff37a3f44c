"""The ``reform-sim`` command: thin subcommands that parse, call one library function, report.

Building the parser imports argparse and this package only (see `sim.cli._common.CommandParser`),
so that ``reform-sim --help`` answers at once.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from sim.cli import (
    _benchmark,
    _calibrate,
    _characterize,
    _data,
    _datasets,
    _demo,
    _detect,
    _evaluate,
    _experiment,
    _generate,
    _policy,
    _scenarios,
    _simulate,
    _stress,
    _train,
)
from sim.cli._common import CliError, CommandParser, check_jobs
from sim.cli._interrupt import sigint_to_main_only

# Each module exposes ``register(subparsers)``, adding its subcommand: a name and help line at
# once, the arguments (and the ``handler`` default) when the subcommand is used.
_COMMANDS = (
    _demo,
    _data,
    _datasets,
    _evaluate,
    _detect,
    _benchmark,
    _experiment,
    _train,
    _characterize,
    _scenarios,
    _simulate,
    _generate,
    _calibrate,
    _stress,
    _policy,
)


# Commands whose finished work survives an interruption (generated shards, the demo's steps, the
# synthetic data of sim2real): run again, they carry on.
_RESUMING = frozenset({"generate", "demo"})
_RESUMING_EXPERIMENTS = frozenset({"sim2real"})
INTERRUPTED = 130  # exit status after Ctrl-C: 128 + SIGINT, as a shell reports it


class _VersionAction(argparse._VersionAction):
    """``--version``: the package's version, read when asked for (``reform`` is not light)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: object,
        option_string: str | None = None,
    ) -> None:
        from reform import __version__

        self.version = f"reform-sim {__version__}"
        super().__call__(parser, namespace, values, option_string)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="reform-sim",
        description=(
            "Simulate social scenes, detect F-formations (REFORM, GCFF), evaluate, log to Rerun."
        ),
    )
    parser.add_argument("--version", action=_VersionAction)
    subparsers = parser.add_subparsers(
        dest="command", metavar="COMMAND", required=True, parser_class=CommandParser
    )
    for module in _COMMANDS:
        module.register(subparsers)
    return parser


def _resumes(args: argparse.Namespace) -> bool:
    """Whether running the command again carries on where it was interrupted."""
    if args.command == "experiment":
        return getattr(args, "experiment", None) in _RESUMING_EXPERIMENTS
    return args.command in _RESUMING


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``reform-sim argv``; returns the exit status (2 for bad input, reported in one
    line on stderr). Ctrl-C raises KeyboardInterrupt to the caller, as any Python call does;
    the console command (:func:`console_main`) reports it instead."""
    return _run(argv, report_interrupt=False)


def console_main() -> int:
    """The ``reform-sim`` console command: :func:`main`, with Ctrl-C reported in one line
    (exit status 130) rather than as a traceback."""
    return _run(None, report_interrupt=True)


def _run(argv: Sequence[str] | None, *, report_interrupt: bool) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        check_jobs(args)
        with sigint_to_main_only():
            return int(args.handler(args) or 0)
    except (CliError, ValueError, OSError, KeyError) as exc:
        # OSError: a file the command reads or writes that the system refuses (permissions, a
        # full disk, a path too long), named by the system's own message.
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"reform-sim {args.command}: error: {_one_line(message)}", file=sys.stderr)
        return 2
    except MemoryError:
        print(
            f"reform-sim {args.command}: error: out of memory (this machine could not hold the "
            "request; ask for less, or use a machine with more memory)",
            file=sys.stderr,
        )
        return 2
    except KeyboardInterrupt:
        if not report_interrupt:
            raise
        again = "; run the same command again to resume" if _resumes(args) else ""
        print(f"reform-sim {args.command}: interrupted{again}", file=sys.stderr)
        return INTERRUPTED


def _one_line(message: object) -> str:
    """An error message on one line, cut to a readable length."""
    text = " ".join(str(message).split("\n"))
    return text if len(text) <= 2000 else text[:1980] + f"… ({len(text):,} characters)"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(console_main())

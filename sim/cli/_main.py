"""What ``reform-sim`` runs once its command line is more than ``--help``: the parser (argparse
and the subcommands' argument modules, added on use) and the command, its errors, interruptions
and stops each reported in one line."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Sequence

from sim.cli import COMMANDS
from sim.cli._common import CliError, CommandParser, add_commands, check_jobs
from sim.cli._exit_guard import EXIT_STATUS, ProcessExit, os_exit_reported
from sim.cli._interrupt import Stopped, as_stopped, sigint_to_main_only, sigterm_stops

# Commands whose finished work survives an interruption (generated shards, the demo's steps, the
# synthetic data of sim2real): run again, they carry on.
_RESUMING = frozenset({"generate", "demo"})
_RESUMING_EXPERIMENTS = frozenset({"sim2real"})
RERUN_LOG = "warn,re_log_encoding=off,re_sdk=off"  # Rerun's log, its sinks' errors left out
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
    parser = CommandParser(
        prog="reform-sim",
        description=(
            "Simulate social scenes, detect F-formations (REFORM, GCFF), evaluate, log to Rerun."
        ),
    )
    parser.add_argument("--version", action=_VersionAction)
    subparsers = parser.add_subparsers(
        dest="command", metavar="COMMAND", required=True, parser_class=CommandParser
    )
    add_commands(subparsers, COMMANDS)
    return parser


def _given_once(parser: argparse.ArgumentParser, argv: Sequence[str]) -> None:
    """Refuses an option that takes one value given twice (``--seed 1 --seed 2``): argparse
    would keep the last without a word. Options that gather their values (``--data A --data
    B``) and flags are left alone."""
    options: dict[str, argparse.Action] = {}
    current, seen = parser, {}
    for k, word in enumerate(argv):
        if word == "--":
            break
        options.update(current._option_string_actions)
        if not word.startswith("-"):
            subcommands = [a for a in current._actions if isinstance(a, argparse._SubParsersAction)]
            if subcommands and word in subcommands[0].choices:
                current = subcommands[0].choices[word]
            continue
        name, equals, value = word.partition("=")
        action = options.get(name)
        if not isinstance(action, argparse._StoreAction):
            continue
        given = f"{name} {value}" if equals else " ".join(argv[k : k + 2])
        if action.dest in seen:
            raise CliError(
                f"{name} is given twice ({seen[action.dest]}, then {given}); give it once"
            )
        seen[action.dest] = given


def _resumes(args: argparse.Namespace) -> bool:
    """Whether running the command again carries on where it was interrupted."""
    if args.command == "experiment":
        return getattr(args, "experiment", None) in _RESUMING_EXPERIMENTS
    return args.command in _RESUMING


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``reform-sim argv``; returns the exit status (2 for bad input, reported in one
    line on stderr). Ctrl-C raises KeyboardInterrupt to the caller, as any Python call does,
    and SIGTERM its subclass `sim.cli._interrupt.Stopped`, once the command has stopped its
    workers; the console command (:func:`console_main`) reports them instead."""
    return _run(argv, report_interrupt=False)


def console_main() -> int:
    """The ``reform-sim`` console command: :func:`main`, with Ctrl-C reported in one line
    (exit status 130) rather than as a traceback, and SIGTERM likewise (status 143)."""
    return _run(None, report_interrupt=True)


def _run(argv: Sequence[str] | None, *, report_interrupt: bool) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    # Rerun's own log of a sink's failure (a full disk) would add lines to the command's one:
    # the command reports it (sim.recording); a RUST_LOG the user set wins.
    os.environ.setdefault("RUST_LOG", RERUN_LOG)
    try:
        _given_once(parser, sys.argv[1:] if argv is None else list(argv))
        check_jobs(args)
        with contextlib.ExitStack() as guards:
            guards.enter_context(os_exit_reported(args.command))
            guards.enter_context(sigterm_stops())
            guards.enter_context(sigint_to_main_only())
            if report_interrupt:  # the console command: a stuck detector may end the process
                from reform.deadline import hard_stops

                guards.enter_context(hard_stops(f"reform-sim {args.command}: error: "))
            return int(args.handler(args) or 0)
    except ProcessExit as exc:  # someone's os._exit, outside a detector's guard
        print(
            f"reform-sim {args.command}: error: {exc} before the command finished", file=sys.stderr
        )
        return EXIT_STATUS
    except BrokenPipeError:  # the reader of stdout left (`reform-sim scenarios | head`): done
        _drop_stdout()
        return 0
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
    except KeyboardInterrupt as caught:
        exc = as_stopped(caught)
        if not report_interrupt:
            if exc is caught:
                raise
            raise exc from None
        again = "; run the same command again to resume" if _resumes(args) else ""
        if isinstance(exc, Stopped):  # SIGTERM: 128 + its number, as a shell reports it
            print(
                f"reform-sim {args.command}: stopped by {exc.signal.name}{again}", file=sys.stderr
            )
            return 128 + exc.signal
        print(f"reform-sim {args.command}: interrupted{again}", file=sys.stderr)
        return INTERRUPTED


def _drop_stdout() -> None:
    """Points stdout at the null device, so that flushing it at exit does not raise again
    (Python's own advice for a closed pipe)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
    except OSError:
        return
    try:
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout is no file (captured): nothing to flush
        pass
    finally:
        os.close(devnull)


def _one_line(message: object) -> str:
    """An error message on one line, cut to a readable length."""
    text = " ".join(str(message).split("\n"))
    return text if len(text) <= 2000 else text[:1980] + f"… ({len(text):,} characters)"

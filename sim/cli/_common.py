"""Pieces the subcommands share, and how a subcommand is declared.

A subcommand is two modules: ``sim/cli/_NAME.py``, its arguments (light: what adding them needs),
and ``sim/cli/NAME.py``, what it does (its libraries imported at the top). `Command` names both
for the command table (`sim.cli.COMMANDS`): building the top-level parser imports neither, a
subcommand's arguments module is imported when that subcommand is parsed or its help is shown
(`CommandParser`), and its run module when it runs (`run_with`).
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple, NoReturn

from sim.cli._command import Command
from sim.cli._numbers import ascii_float, ascii_int

if TYPE_CHECKING:
    from sim.sizing import RequestTooLarge

# reform.datasets' FORMATS and their aliases, and LENGTH_UNITS, kept here so that building the
# parser imports nothing heavy (tests/sim/cli/test_cli_options.py checks that they agree).
FORMATS = ("salsa", "dante", "babble", "gcff", "parquet")
LENGTH_UNITS = ("cm", "m", "px")
# The time units of reform.datasets._validation.TIME_UNITS, kept here for the same reason
# (tests/reform/datasets/test_datasets_time_units.py checks that they agree).
TIME_UNITS = ("s", "ms", "us", "ns")
# Default share of each sequence's annotated frames, by time, that trains (reform.time_split's).
TRAIN_FRACTION = 0.6
DEFAULT_DATASETS = "../shared/datasets"  # the real datasets beside a clone
DATASETS_VARIABLE = "REFORM_SIM_DATASETS"  # environment variable naming them elsewhere
DEFAULT_JOBS = "every core"  # what --jobs is when not given, in every command (`job_count`)


def read_text(option: str, path: str, *, expected: str) -> str:
    """The UTF-8 text of the file ``option`` names; a `CliError` naming the option and the file
    when it cannot be read or is not UTF-8 text (``expected`` says what it should hold)."""
    from reform.atomic import file_kind  # here: building the parser imports no reform module

    kind = file_kind(Path(path))
    if kind != "a file":
        raise CliError(f"{option} {path}: expected {expected} in a file, found {kind}")
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise CliError(f"{option} {path}: cannot read it ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise CliError(
            f"{option} {path}: expected {expected}, found byte 0x{exc.object[exc.start]:02x} "
            f"at offset {exc.start} that is not UTF-8"
        ) from None


def refuse_given_twice(
    option: str, given: Sequence[tuple[str, Any]], *, kind: str = "dataset"
) -> None:
    """Refuses a dataset (or another ``kind`` of input) given twice, as it would count twice:
    ``given`` holds each value as typed with where it is; the second value of one place is
    named, with the first."""
    seen: dict[Any, str] = {}
    for value, location in given:
        if location in seen:
            raise CliError(
                f"{option} {value}: {kind} {location} is given twice (also as {option} "
                f"{seen[location]}); give each {kind} once"
            )
        seen[location] = value


def default_datasets() -> str | None:
    """The real datasets' folder when none is given: ``$REFORM_SIM_DATASETS`` when set, else
    ``../shared/datasets`` when that folder exists, else None
    (`reform.datasets.local_datasets_dir`)."""
    from reform.datasets import local_datasets_dir

    folder = local_datasets_dir()
    return None if folder is None else str(folder)


class CliError(Exception):
    """A user-facing error: printed as one line by ``reform-sim``, exit status 2."""


class CommandParser(argparse.ArgumentParser):
    """The parser of a subcommand, its arguments added on first use, and its errors in one line.

    ``subparsers.add_parser(name, help=..., arguments=add)`` registers the subcommand at once
    (its name and help line) and calls ``add(parser)`` only when the subcommand is parsed or its
    usage or help is formatted, so that ``reform-sim --help`` and every other subcommand do not
    import what this one's arguments need. ``add`` also sets the ``handler`` default.
    """

    def __init__(
        self,
        *args: Any,
        arguments: Callable[[argparse.ArgumentParser], None] | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(*args, **kwargs)
        self._add_arguments = arguments

    def _ensure_arguments(self) -> None:
        add, self._add_arguments = self._add_arguments, None
        if add is not None:
            add(self)

    def parse_known_args(
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self._ensure_arguments()
        self._given = list(sys.argv[1:] if args is None else args)
        namespace, extras = super().parse_known_args(args, namespace)
        if extras and not self._has_subcommands():  # nothing below this parser takes them
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras

    def _has_subcommands(self) -> bool:
        return any(isinstance(a, argparse._SubParsersAction) for a in self._actions)

    def _unknown_flags(self) -> list[str]:
        """The flags given to this parser that none of its options is, nor abbreviates."""
        unknown = []
        for word in getattr(self, "_given", ()):
            if word == "--":
                break
            flag = word.partition("=")[0]
            if not flag.startswith("-") or flag == "-" or self._negative_number_matcher.match(flag):
                continue
            if not any(option.startswith(flag) for option in self._option_string_actions):
                unknown.append(flag)
        return unknown

    def _suggestions(self) -> str:
        """``; did you mean --jobs?`` for each unknown flag close to one this parser takes."""
        shown = [
            flag
            for action in self._actions
            if action.help is not argparse.SUPPRESS
            for flag in action.option_strings
            if flag.startswith("--")
        ]
        close = {
            flag: match[0]
            for flag in self._unknown_flags()
            if (match := difflib.get_close_matches(flag, shown, n=1, cutoff=0.6))
        }
        if len(close) == 1:
            return f"; did you mean {next(iter(close.values()))}?"
        said = [f"{match} for {flag}" for flag, match in close.items()]
        return f"; did you mean {', '.join(said)}?" if said else ""

    def format_usage(self) -> str:
        self._ensure_arguments()
        return super().format_usage()

    def format_help(self) -> str:
        self._ensure_arguments()
        return super().format_help()

    def error(self, message: str) -> NoReturn:
        """A malformed command line in one line, as every other error: what was wrong and where
        the usage is (argparse prints the whole usage first). A flag none of the command's
        options is comes first, with the closest one the command takes (argparse names
        neither: a misspelt required flag is otherwise reported as missing)."""
        unknown = self._unknown_flags()
        if unknown and not message.startswith("unrecognized arguments"):
            message = f"unrecognized arguments: {' '.join(unknown)}"
        if unknown:
            message += self._suggestions()
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def add_commands(subparsers: argparse._SubParsersAction, commands: Sequence[Command]) -> None:
    """Adds each command of ``commands`` to ``subparsers``: its name and help line now, its
    arguments (importing its arguments module) when it is used."""
    for command in commands:
        subparsers.add_parser(
            command.name,
            aliases=list(command.aliases),
            help=command.help,
            formatter_class=argparse.RawDescriptionHelpFormatter,
            arguments=_arguments_of(command.arguments),
        )


class Action(NamedTuple):
    """One action of a subcommand that has several (``reform-sim data info``).

    Attributes:
        name: what is typed after the subcommand.
        help: its line in the subcommand's help.
        description: its own help's text.
        arguments: adds its arguments to its parser and sets the ``handler`` default
            (`run_with`); called when the action is parsed or its help shown.
        as_written: the description is shown as written (False: argparse re-wraps it).
    """

    name: str
    help: str
    description: str
    arguments: Callable[[argparse.ArgumentParser], None]
    as_written: bool = True


def add_actions(
    parser: argparse.ArgumentParser, actions: Sequence[Action], *, required: bool = True
) -> None:
    """Adds ``actions`` to ``parser`` as its ``ACTION`` (``args.action``), in order."""
    subparsers = parser.add_subparsers(dest="action", metavar="ACTION", required=required)
    for action in actions:
        subparsers.add_parser(
            action.name,
            help=action.help,
            description=action.description,
            formatter_class=(
                argparse.RawDescriptionHelpFormatter
                if action.as_written
                else argparse.HelpFormatter
            ),
            arguments=action.arguments,
        )


def _arguments_of(module_name: str) -> Callable[[argparse.ArgumentParser], None]:
    def add(parser: argparse.ArgumentParser) -> None:
        module = importlib.import_module(module_name)
        parser.description = module.DESCRIPTION
        module.add_arguments(parser)

    return add


def run_with(target: str) -> Callable[[argparse.Namespace], int]:
    """The handler ``module:function``, imported when the command runs (so that its arguments
    and its help do not import what it runs on)."""
    module_name, function = target.split(":")

    def handler(args: argparse.Namespace) -> int:
        return getattr(importlib.import_module(module_name), function)(args)

    handler.target = target  # type: ignore[attr-defined]
    return handler


def check_output(
    option: str,
    path: str | os.PathLike[str] | None,
    *,
    folder: bool = False,
    suffix: str | None = None,
) -> None:
    """Raises `CliError` unless ``path`` can be written: a file (or, with ``folder``, a folder
    of outputs), checked before the command's work starts. Nothing is created.

    Args:
        option: the flag that named the path, e.g. ``"--json"``.
        path: the path given; None (the option not given) passes.
        folder: the command writes files into ``path`` rather than ``path`` itself.
        suffix: the ending the file's name must have (the format written, e.g. ``".parquet"``).

    Raises:
        CliError: e.g. ``--json out: expected a file path, found an existing folder``.
    """
    if path is None:
        return
    if not str(path):
        raise CliError(f"{option}: expected a path, found an empty one")
    from reform.datasets.store import is_uri

    if is_uri(path):  # never a local folder named "s3:"
        raise CliError(
            f"{option} {path}: expected a path on this machine (only reform-sim generate --out "
            "writes to object storage); write it here and copy it to the store"
        )
    from reform.atomic import OutputPathError, check_file_path, check_folder_path

    try:
        (check_folder_path if folder else check_file_path)(path)
    except OutputPathError as exc:
        raise CliError(f"{option} {exc}") from None
    if suffix is not None and Path(path).suffix.lower() != suffix:
        raise CliError(
            f"{option} {path}: expected a file name ending in {suffix} (the format written), "
            f"found {Path(path).suffix or 'no ending'}"
        )


def twin_data_name(args: argparse.Namespace) -> str:
    """How a message names the twin's generated dataset: ``--twin-data`` when given, else the
    folder beside the twin file that stands for it."""
    return "--twin-data" if args.twin_data else "the twin's data folder"


def check_recording(args: argparse.Namespace) -> None:
    """Checks the Rerun recording flags (``--save PATH.rrd``, ``--url`` with ``--connect``) up
    front, as :func:`check_output` does the other outputs."""
    from sim.recording import target_from_args

    target_from_args(args)  # a ValueError naming the flag: not .rrd, --url without --connect
    check_output("--save", getattr(args, "save", None))


def check_jobs(args: argparse.Namespace) -> None:
    """Raises `CliError` unless ``--jobs`` (when the command has it and it is given) is >= 1."""
    jobs = getattr(args, "jobs", None)
    if jobs is not None and jobs < 1:
        raise CliError(f"--jobs must be >= 1, got {jobs}")


def add_max_memory_argument(parser: argparse.ArgumentParser, *, holds: str) -> None:
    """``--max-memory SIZE``: the memory a command may take, read by :func:`max_memory`.

    Args:
        holds: what the command holds in memory that streaming does not bound, for the help.
    """
    parser.add_argument(
        "--max-memory",
        default=None,
        metavar="SIZE",
        help=f"memory the run may take, e.g. 8G or 512M (default: what this machine has "
        f"available); {holds}",
    )


def add_dry_run_argument(parser: argparse.ArgumentParser) -> None:
    """``--dry-run``: size the run, state its estimate (or refuse it) and stop before any work."""
    parser.add_argument(
        "--dry-run",
        action="store_true",
        help="check the arguments, state the run's estimate of time, memory and disk (or "
        "refuse it, as the run would) and stop before any work",
    )


def max_memory(args: argparse.Namespace) -> int | None:
    """``--max-memory`` in bytes (None when not given); a `CliError` for a malformed size."""
    text = getattr(args, "max_memory", None)
    if text is None:
        return None
    from sim.sizing import parse_size

    try:
        return parse_size(text)
    except ValueError as exc:
        raise CliError(f"--max-memory: {exc}") from None


def frame_memory_limit(args: argparse.Namespace) -> tuple[int, str]:
    """The bytes one frame may take a detector (``--max-memory``, else the memory this machine
    has available now) and how a message names that limit."""
    from sim.sizing import available_memory, format_size

    limit = max_memory(args)
    if limit is not None:
        return limit, f"--max-memory {format_size(limit)}"
    limit = available_memory()
    return limit, f"the {format_size(limit)} of memory this machine has available"


def size_error(exc: RequestTooLarge, flags: dict[str, str] | None = None) -> CliError:
    """A `sim.sizing.RequestTooLarge` as the command's one line, its parameters spelled as
    flags: ``max_memory`` as ``--max-memory``, the others as ``flags`` says
    (``{"out_dir": "--out"}``)."""
    from sim.sizing import flag_name

    return CliError(exc.message(lambda name: flag_name(name, flags)))


def add_data_arguments(parser: argparse.ArgumentParser, *, old_positional: bool = False) -> None:
    """``--data PATH|NAME [--format F] [--units cm|m|px] [--time-unit s|ms|us|ns]``: where a
    dataset is and how to read it.

    The dataset is a path, or a name that :func:`load_data` resolves (`reform.datasets.resolve`):
    a fetched public dataset (``reform-sim datasets list``) or a folder among the real datasets.

    Args:
        parser: the subcommand's parser.
        old_positional: the dataset may still be given as a positional path, its former
            spelling (read with a warning by :func:`data_path`).
    """
    add_data_argument(parser, old_positional=old_positional)
    parser.add_argument(
        "--format",
        choices=FORMATS,
        default=None,
        help="dataset format (default: detected from the path)",
    )
    add_unit_arguments(parser)
    parser.add_argument(
        "--strict",
        action="store_true",
        help="refuse the quirks a loader otherwise repairs and counts in its report (ground truth "
        "naming people absent from the features, NaN poses, ...)",
    )
    parser.add_argument(
        "--allow-incomplete",
        action="store_true",
        help="read an unfinished `reform-sim generate` folder: the episodes written so far",
    )


def add_jobs_argument(parser: argparse.ArgumentParser, *, does: str = "worker processes") -> None:
    """``--jobs N``: the local processes a command's work runs on, default `DEFAULT_JOBS` in
    every command (None until :func:`job_count` reads it); ``does``: what they do, for the help."""
    parser.add_argument(
        "--jobs",
        type=ascii_int,
        default=None,
        metavar="N",
        help=f"{does} (default: {DEFAULT_JOBS}); results do not depend on it",
    )


def job_count(args: argparse.Namespace) -> int:
    """``--jobs`` as a count of processes: the number given, else every core this process may
    run on (`DEFAULT_JOBS`)."""
    if args.jobs is not None:
        return args.jobs
    from sim.executor import cpu_count

    return cpu_count()


def add_backend_arguments(
    parser: argparse.ArgumentParser, *, jobs_help: str = "worker processes"
) -> None:
    """``--jobs N``, ``--backend local|ray`` and ``--address ADDR``: where a command's
    independent units of work run (`sim.executor.Executor`), checked by :func:`check_backend`
    and made into an executor by :func:`executor_from_args`.

    Args:
        jobs_help: what the local processes do, for the help.
    """
    add_jobs_argument(parser, does=f"{jobs_help} with --backend local")
    parser.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="local: worker processes on this machine (--jobs); ray: Ray tasks on every CPU of "
        "the cluster at --address, or of a Ray instance started on this machine without it; "
        "the results are the same",
    )
    parser.add_argument(
        "--address",
        default=None,
        metavar="ADDR",
        help="Ray cluster address with --backend ray: HOST:PORT (what `ray start --head` "
        "prints), ray://HOST:PORT, or auto (the cluster running on this machine)",
    )


def check_backend(args: argparse.Namespace) -> None:
    """Raises `CliError` for ``--address`` without Ray, ``--jobs`` with it, Ray not installed,
    or an ``--address`` where no cluster answers (probed in seconds, before any work:
    `sim.executor.check_address`)."""
    if args.address is not None and args.backend != "ray":
        raise CliError(f"--address needs --backend ray, got --backend {args.backend}")
    if args.jobs is not None and args.backend == "ray":
        raise CliError(
            "--jobs sets local worker processes (--backend local); with --backend ray every CPU "
            "of the Ray cluster works (a local one when --address is not given)"
        )
    if args.backend != "ray":
        return
    from sim.executor import ClusterError, check_address, import_ray

    if args.address is not None:  # first: it needs no Ray, and answers in seconds
        try:
            check_address(args.address)
        except ClusterError as exc:
            raise CliError(f"--{exc}") from None
    try:
        import_ray()
    except ImportError as exc:
        raise CliError(f"--backend ray: {exc}") from None


def backend_words(args: argparse.Namespace) -> list[str]:
    """``--jobs``, ``--backend`` and ``--address`` as given, as command-line words (for the
    command a report records)."""
    words = [] if args.jobs is None else ["--jobs", str(args.jobs)]
    if args.backend != "local":
        words += ["--backend", args.backend]
    if args.address is not None:
        words += ["--address", args.address]
    return words


def executor_from_args(args: argparse.Namespace, *, progress: bool = True):
    """The `sim.executor.Executor` that ``--backend``, ``--jobs`` and ``--address`` ask for,
    checked first (:func:`check_backend`); use it as a context manager."""
    check_backend(args)
    from sim.executor import Executor

    return Executor(args.backend, jobs=args.jobs, address=args.address, progress=progress)


def add_train_fraction_argument(
    parser: argparse.ArgumentParser,
    *,
    help: str,  # noqa: A002
    default: float | None = TRAIN_FRACTION,
) -> None:
    """``--train-fraction F``: the training share of `reform.time_split`, checked by
    :func:`check_train_fraction` (``default`` None: tell "not given" from the default)."""
    parser.add_argument(
        "--train-fraction", type=ascii_float, default=default, metavar="F", help=help
    )


def check_train_fraction(args: argparse.Namespace) -> None:
    """Raises `CliError` unless ``--train-fraction`` lies in (0, 1)."""
    if not 0.0 < args.train_fraction < 1.0:
        raise CliError(f"--train-fraction must lie in (0, 1), got {args.train_fraction}")


def add_data_argument(
    parser: argparse.ArgumentParser, *, old_positional: bool = False, metavar: str = "PATH|NAME"
) -> None:
    """``--data PATH|NAME`` alone (required); with ``old_positional``, also the former
    positional spelling, hidden (:func:`data_path` settles the two)."""
    text = (
        "dataset file or folder (or its URI in a store: s3://bucket/prefix, credentials from "
        "the environment), or a dataset's name: a fetched public dataset "
        f"(reform-sim datasets list) or a folder in ${DATASETS_VARIABLE} (else {DEFAULT_DATASETS})"
    )
    parser.add_argument("--data", required=not old_positional, metavar=metavar, help=text)
    if old_positional:
        parser.add_argument("old_path", nargs="?", default=None, help=argparse.SUPPRESS)


def warn_deprecated(old: str, new: str) -> None:
    """The line on stderr with which a former spelling ``old`` still works for one release:
    it names ``new``, the spelling that replaces it."""
    print(f"warning: {old} is deprecated and goes in the next release; use {new}", file=sys.stderr)


def data_path(args: argparse.Namespace) -> str:
    """``--data``, or the positional path of the former spelling (with a warning); sets
    ``args.data``."""
    old = getattr(args, "old_path", None)
    if old is not None:
        if args.data is not None:
            raise CliError(f"give the dataset once: --data {args.data}, or {old}, not both")
        warn_deprecated(f"the dataset as a positional path ({old})", f"--data {old}")
        args.data, args.old_path = old, None
    if args.data is None:
        raise CliError("--data PATH|NAME is required: the dataset to read")
    return args.data


def check_frames(args: argparse.Namespace) -> None:
    """Checks ``--frames`` and ``--train-fraction`` (`sim.cli._grammar.add_frames`) up front:
    a fraction in (0, 1), and only where it splits (``--frames train|test``); sets the default
    fraction."""
    if args.train_fraction is None:
        args.train_fraction = TRAIN_FRACTION
        return
    check_train_fraction(args)
    if args.frames in (None, "all"):
        raise CliError(
            f"--train-fraction {args.train_fraction:g} splits the frames for --frames "
            "train|test; with --frames all every annotated frame counts"
        )


def select_frames(args: argparse.Namespace, frames: Sequence[Any], *, doing: str) -> list[Any]:
    """The annotated ``frames`` that ``--frames`` names: all, or the train or test part of
    `reform.time_split` (``--train-fraction``); a `CliError` naming the dataset when none is
    left (``doing`` says what they were for)."""
    from reform import time_split

    frames = [frame for frame in frames if frame.annotated]
    if not frames:
        raise CliError(f"{args.data}: the dataset has no annotated frames to {doing}")
    if args.frames != "all":
        train, test = time_split(frames, args.train_fraction)
        frames = train if args.frames == "train" else test
        if not frames:
            raise CliError(f"{args.data}: the {args.frames} part of the split holds no frames")
    return frames


def load_data(args: argparse.Namespace):
    """Loads the dataset named by :func:`add_data_arguments`: a path, or a dataset's name
    (`reform.datasets.resolve`; an unfetched public dataset's error says how to fetch it)."""
    from reform.datasets import load_dataset, resolve
    from reform.datasets.summary import repairs_line

    data_path(args)

    if args.units == "px" and args.metres_per_pixel is None:
        raise CliError("--units px needs --metres-per-pixel M: pixels are never read as metres")
    if args.metres_per_pixel is not None and args.units != "px":
        raise CliError(f"--metres-per-pixel is the scale of --units px, got --units {args.units}")
    dataset = load_dataset(
        resolve(args.data),
        format=args.format,
        units=args.units,
        metres_per_pixel=args.metres_per_pixel,
        strict=args.strict,
        allow_incomplete=args.allow_incomplete,
        time_unit=getattr(args, "time_unit", None),
    )
    repaired = repairs_line(dataset, str(args.data))
    if repaired:
        print(repaired, file=sys.stderr)
    missing = dataset.metadata.get("incomplete")
    if missing:  # read on purpose (--allow-incomplete): say what is left out
        print(
            f"warning: {args.data}: {len(missing)} shard(s) left out "
            f"(--allow-incomplete): {missing[0]}" + (" …" if len(missing) > 1 else ""),
            file=sys.stderr,
        )
    return dataset


# Sensor flags: field of sim.Sensor -> (flag, unit shown in the help).
_SENSOR_NUMBERS = {
    "fov_deg": ("--fov-deg", "DEG", "horizontal field of view, degrees"),
    "min_range": ("--min-range", "M", "nearest distance seen, metres"),
    "max_range": ("--max-range", "M", "farthest distance seen, metres"),
    "position_noise": ("--position-noise", "M", "position noise per axis (std), metres"),
    "yaw_noise": ("--yaw-noise", "RAD", "yaw noise (std), radians"),
    "dropout": ("--dropout", "P", "probability that a seen person is missed"),
}
_SENSOR_SWITCHES = {
    "occlusion": ("--occlusion", "other bodies hide people (default: yes)"),
    "include_robot": ("--include-robot", "the observed frames hold the robot (default: yes)"),
}


def add_overrides_argument(parser: argparse.ArgumentParser) -> None:
    """``--set KEY=VALUE`` (repeatable): scenario options, read by :func:`parse_overrides`."""
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        dest="overrides",
        help="scenario option (reform-sim scenarios lists them); repeatable",
    )


def add_view_argument(parser: argparse.ArgumentParser) -> None:
    """``--view truth|robot``: the ground truth or the robot sensor's view (see
    :func:`add_sensor_arguments`)."""
    parser.add_argument(
        "--view",
        choices=("truth", "robot"),
        default="truth",
        help="ground truth, or what the robot's head sensor observes",
    )


def add_sensor_arguments(parser: argparse.ArgumentParser) -> None:
    """The robot sensor's flags (fields of `sim.Sensor`), used with ``--view robot``."""
    sensor = parser.add_argument_group("sensor (with --view robot)")
    for name, (flag, metavar, text) in _SENSOR_NUMBERS.items():
        sensor.add_argument(
            flag, dest=f"sensor_{name}", type=ascii_float, default=None, metavar=metavar, help=text
        )
    for name, (flag, text) in _SENSOR_SWITCHES.items():
        sensor.add_argument(
            flag,
            dest=f"sensor_{name}",
            action=argparse.BooleanOptionalAction,
            default=None,
            help=text,
        )


def parse_overrides(
    scenario: str, items: list[str], *, duration: float | None = None
) -> dict[str, Any]:
    """``--set`` items (``["people=18", "robot=true"]``) as typed options of ``scenario``;
    ``duration``: the command's ``--duration``, refused beside a ``--set duration=`` (one of the
    two would be dropped)."""
    import scenarios

    pairs: dict[str, str] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise CliError(f"--set must be KEY=VALUE, got {item!r}")
        if key in pairs:
            raise CliError(f"--set {key} given twice")
        if key == "duration" and duration is not None:
            raise CliError(
                f"--duration {duration:g} and --set duration={text} both give the episode's "
                "length; give one"
            )
        pairs[key] = text
    if not pairs:
        return {}
    return scenarios.parse_options(scenario, pairs)


def sensor_options(args: argparse.Namespace) -> dict[str, Any] | None:
    """The sensor flags given (``None`` for the ground-truth view, where they are an error)."""
    given = {
        name: getattr(args, f"sensor_{name}")
        for name in (*_SENSOR_NUMBERS, *_SENSOR_SWITCHES)
        if getattr(args, f"sensor_{name}") is not None
    }
    if args.view == "truth":
        if given:
            flags = [(_SENSOR_NUMBERS | _SENSOR_SWITCHES)[n][0] for n in given]
            raise CliError(f"sensor options need --view robot, got {', '.join(flags)}")
        return None
    return given


def temporal_tolerance(args: argparse.Namespace, frames: Sequence[Any]) -> float | None:
    """``--temporal``'s matching window for ``frames``, checked before any detector runs (None
    without ``--temporal``): ``--tolerance``, else 1 s or the frames' interval where longer;
    a `CliError` naming the sequence and the frame when the frames cannot be scored in time."""
    if args.tolerance is not None and not args.temporal:
        raise CliError("--tolerance is the matching window of --temporal; give --temporal too")
    if not args.temporal:
        return None
    from reform.temporal import DEFAULT_TOLERANCE_S, check_temporal, frame_interval

    try:
        tolerance = args.tolerance
        if tolerance is None:
            tolerance = max(DEFAULT_TOLERANCE_S, frame_interval(frames))
        return check_temporal(frames, tolerance)
    except ValueError as exc:
        raise CliError(f"--temporal: {args.data}: {' '.join(str(exc).split())}") from None


def add_unit_arguments(parser: argparse.ArgumentParser, *, whose: str = "the file's") -> None:
    """``--units cm|m|px``, ``--time-unit s|ms|us|ns`` and ``--metres-per-pixel M``: how to read
    ``whose`` positions and time stamps (`reform.datasets.load_dataset`)."""
    parser.add_argument(
        "--units",
        choices=LENGTH_UNITS,
        default=None,
        help=f"length unit of {whose} positions (GCFF folders: default cm; DANTE text: "
        "default m; px for image pixels with --metres-per-pixel; Babble and Parquet are metres)",
    )
    parser.add_argument(
        "--time-unit",
        choices=TIME_UNITS,
        default=None,
        help=f"unit of {whose} time stamps (GCFF timestamp, DANTE t; default: seconds as "
        "stored below 1e8, larger ones read as Unix times in the unit their magnitude and "
        "spacing show, counted from each sequence's start; Babble and Parquet are seconds)",
    )
    parser.add_argument(
        "--metres-per-pixel",
        type=ascii_float,
        default=None,
        metavar="M",
        help="with --units px: the scale of the pixel positions, metres per pixel",
    )

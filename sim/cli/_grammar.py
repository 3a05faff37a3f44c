"""The one grammar of ``reform-sim``'s commands, and the builders every subcommand uses to keep it.

Each concept has one spelling across the subcommands (``tests/sim/cli/test_cli_grammar.py``
walks every parser and checks it):

=================  =====================================================================
data in            ``--data PATH|NAME`` (repeatable where a command reads several;
                   ``NAME=PATH`` says which dataset a path is)
results out        ``--out DIR`` where a command writes several files, ``--out FILE`` where
                   it writes exactly one; an optional ``--out`` states its default in the help
seed               ``--seed S``, default 0
counts             ``--episodes N``
parallel work      ``--jobs N``, default every core (``DEFAULT_JOBS``) in every command (with
                   ``--backend``/``--address`` where Ray can run it); ``benchmark`` starts no
                   more workers than its cells pay for (``CELLS_PER_WORKER``)
progress           bars and lines on stderr; ``--quiet`` silences them
one recording      ``--save PATH.rrd``, ``--connect [--url URL]``, ``--serve``, ``--headless``
                   (the flags of ``rr.script_add_args``)
recordings         ``--recordings/--no-recordings``: one ``.rrd`` per item in OUT/recordings/
frames scored      ``--frames all|train|test`` with ``--train-fraction F``
=================  =====================================================================

Old spellings keep working for one release: `rename` declares one, hidden from the help, which
prints a line naming the new spelling and then does what the new one does. A flag a command does
not take is refused with the closest one it does (`sim.cli._common.CommandParser`), and an
unknown scenario with the registry's one message (`scenarios.describe`).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from sim.cli._common import TRAIN_FRACTION, check_output, run_with, warn_deprecated
from sim.cli._numbers import ascii_float, ascii_int
from sim.progress import elapsed_line, progress_bar
from sim.ticking import ticking

DEFAULT_SEED = 0
FRAME_CHOICES = ("all", "train", "test")

# old spelling -> new, as `rename` declared them (for the grammar test and the docs)
RENAMED: dict[str, str] = {}


class _Renamed(argparse.Action):
    """An old spelling: says which spelling replaces it, then applies the value as that does.

    ``options`` are argparse's own (`rename` passes ``nargs``, ``metavar`` and ``type``)."""

    def __init__(
        self,
        option_strings: Sequence[str],
        dest: str,
        *,
        new: str,
        apply: Callable[[argparse.Namespace, Any], None],
        **options: Any,
    ) -> None:
        super().__init__(option_strings, argparse.SUPPRESS, help=argparse.SUPPRESS, **options)
        self.new = new
        self.apply = apply

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        warn_deprecated(option_string, self.new)
        self.apply(namespace, values)


def rename(
    parser: argparse.ArgumentParser | argparse._ArgumentGroup,
    old: str,
    new: str,
    apply: Callable[[argparse.Namespace, Any], None],
    *,
    nargs: int | str | None = None,
    metavar: str | None = None,
    type: Callable[[str], Any] | None = None,  # noqa: A002
) -> None:
    """Declares ``old``, a former spelling of ``new``: hidden, it warns and calls
    ``apply(namespace, value)`` with the value converted by ``type`` (``nargs=0``: a switch)."""
    RENAMED[old] = new
    parser.add_argument(
        old, action=_Renamed, new=new, apply=apply, nargs=nargs, metavar=metavar, type=type
    )


def setter(dest: str, value: Any = None) -> Callable[[argparse.Namespace, Any], None]:
    """``apply`` for `rename`: stores the given value in ``dest`` (``value`` for a switch)."""

    def apply(namespace: argparse.Namespace, given: Any) -> None:
        setattr(namespace, dest, given if value is None else value)

    return apply


def appender(dest: str, form: Callable[[Any], Any] = lambda v: v) -> Callable[..., None]:
    """``apply`` for `rename`: appends ``form(value)`` to the list in ``dest``."""

    def apply(namespace: argparse.Namespace, given: Any) -> None:
        items = list(getattr(namespace, dest, None) or [])
        items.append(form(given))
        setattr(namespace, dest, items)

    return apply


# The largest seed a command takes: seeds are kept as 64-bit integers (a dataset's card, a twin
# file: sim.twins.description.MAX_SEED), so a larger one would be refused by the next command.
MAX_SEED = 2**63 - 1


def _seed(text: str) -> int:
    """A ``--seed`` value: a whole number from 0 to `MAX_SEED`."""
    try:
        value = ascii_int(text)
    except ValueError:
        value = None
    if value is None or not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(
            f"expected a whole number from 0 to {MAX_SEED}, found {text!r}"
        )
    return value


def add_seed(parser: argparse.ArgumentParser, *, help: str = "master seed") -> None:  # noqa: A002
    """``--seed S``, default 0 (0 to `MAX_SEED`)."""
    parser.add_argument(
        "--seed", type=_seed, default=DEFAULT_SEED, metavar="S", help=f"{help} (default 0)"
    )


def add_episodes(
    parser: argparse.ArgumentParser,
    *,
    help: str,  # noqa: A002
    default: int | None = None,
    required: bool = False,
    old: str | None = None,
) -> None:
    """``--episodes N`` (``old``: its former spelling, e.g. ``--seeds``)."""
    parser.add_argument(
        "--episodes", type=ascii_int, default=default, required=required, metavar="N", help=help
    )
    if old is not None:
        rename(parser, old, "--episodes", setter("episodes"), metavar="N", type=ascii_int)


def add_quiet(parser: argparse.ArgumentParser, *, old: Sequence[str] = ("--no-progress",)) -> None:
    """``--quiet``: no progress on stderr (``old``: the former ``--no-progress``)."""
    parser.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bars or lines on stderr"
    )
    for spelling in old:
        rename(parser, spelling, "--quiet", setter("quiet", True), nargs=0)


def show_progress(args: argparse.Namespace) -> bool:
    """Whether a short command shows its progress lines: not ``--quiet``, and stderr a
    terminal (a log or a pipe gets the result and errors alone)."""
    return not getattr(args, "quiet", False) and sys.stderr.isatty()


@contextlib.contextmanager
def ticking_bar(
    args: argparse.Namespace, what: str, count: int, *, unit: str = "frame"
) -> Iterator[None]:
    """Where a short command shows its progress (`show_progress`), a bar of ``count`` units
    redrawn every few seconds while the block does ``what`` with them all in one call (GTCG
    predicting SALSA, REFORM fitting on it: a minute, half a minute on two cores), full when
    the block ends and then cleared: the line that follows says what was done, and a refusal
    stays one line."""
    bar = progress_bar(
        total=count,
        desc=what,
        unit=unit,
        file=sys.stderr,
        leave=False,
        disable=not show_progress(args),
    )
    with bar, ticking(bar):
        yield
        bar.update(count)


@contextlib.contextmanager
def stage_lines(
    args: argparse.Namespace, what: str, *, stamp: bool = True
) -> Iterator[Callable[[str], None]]:
    """``progress(message)`` for a long command that names its stages: each message a line
    on stderr, ``[  12.3 s] message`` with ``stamp`` (none with ``--quiet``) and, where the
    command shows its progress (`show_progress`), a line under them with the time so far,
    redrawn while a stage works (a classifier's cross-validation: a minute on two cores)."""
    started = time.perf_counter()
    bar = elapsed_line(what, disable=not show_progress(args))

    def progress(message: str) -> None:
        if getattr(args, "quiet", False):
            return
        line = f"[{time.perf_counter() - started:6.1f} s] {message}" if stamp else message
        if bar.disable:
            print(line, file=sys.stderr, flush=True)
        else:
            bar.write(line, file=sys.stderr)

    with bar, ticking(bar):
        yield progress


def run_loading(target: str, loads: str) -> Callable[[argparse.Namespace], int]:
    """`run_with`'s handler of ``target`` (``module:function``) for a command whose module
    imports heavy libraries (MuJoCo, scikit-learn, Rerun, torch: 2 to 7 s on two busy cores):
    where it shows its progress (`show_progress`), a line ``loading {loads}: 00:03 so far``
    redrawn while the module imports, cleared when the command begins. A log or a pipe gets
    nothing more."""
    handler = run_with(target)
    module = target.split(":")[0]

    def loading(args: argparse.Namespace) -> int:
        if module not in sys.modules and show_progress(args):
            with stage_lines(args, f"loading {loads}", stamp=False):
                importlib.import_module(module)
        return handler(args)

    loading.target = target  # type: ignore[attr-defined]
    return loading


def add_out(
    parser: argparse.ArgumentParser,
    *,
    folder: bool,
    help: str,  # noqa: A002
    default: str | None = None,
    metavar: str | None = None,
) -> None:
    """``--out DIR`` (``folder``: the command writes several files) or ``--out FILE``."""
    parser.add_argument(
        "--out",
        required=default is None,
        default=default,
        metavar=metavar or ("DIR" if folder else "FILE"),
        help=help if default is None else f"{help} (default: {default})",
    )


class _Recordings(argparse.Action):
    """``--recordings/--no-recordings``; with ``folder``, ``--recordings DIR`` (the former
    spelling of an experiment's) still names the folder, with a warning."""

    def __init__(
        self,
        option_strings: Sequence[str],
        dest: str,
        *,
        default: bool = False,
        help: str | None = None,  # noqa: A002
        folder: bool = False,
    ) -> None:
        strings = [*option_strings, *(f"--no-{s[2:]}" for s in option_strings)]
        super().__init__(
            strings,
            dest,
            nargs="?" if folder else 0,
            default=default,
            help=help,
            metavar="DIR" if folder else None,
        )

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        if option_string is not None and option_string.startswith("--no-"):
            setattr(namespace, self.dest, False)
        elif values:
            warn_deprecated(f"{option_string} {values}", f"{option_string} (OUT/recordings/)")
            setattr(namespace, self.dest, values)
        else:
            setattr(namespace, self.dest, True)

    def format_usage(self) -> str:
        return " | ".join(self.option_strings)


def add_report_out(parser: argparse.ArgumentParser, *, basename: str, holds: str) -> None:
    """``--out DIR``: BASENAME.json and BASENAME.md in DIR (``holds``: what the JSON holds);
    the former ``--json FILE`` and ``--markdown FILE`` still name the files (`report_outputs`)."""
    parser.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help=f"write {basename}.json ({holds}) and {basename}.md in this folder (default: "
        "printed only)",
    )
    parser.set_defaults(old_json=None, old_markdown=None)
    rename(parser, "--json", "--out DIR", setter("old_json"), metavar="FILE")
    rename(parser, "--markdown", "--out DIR", setter("old_markdown"), metavar="FILE")


def report_outputs(args: argparse.Namespace, basename: str) -> dict[str, tuple[str, Path]]:
    """The files `add_report_out`'s flags name, by kind (``json``, ``markdown``), with the
    option naming each; each checked writable before any work."""
    outputs = {}
    if args.out is not None:
        check_output("--out", args.out, folder=True)
        out = Path(args.out)
        outputs = {
            "json": ("--out", out / f"{basename}.json"),
            "markdown": ("--out", out / f"{basename}.md"),
        }
    for kind, option in (("json", "--json"), ("markdown", "--markdown")):
        path = getattr(args, f"old_{kind}")
        if path is not None:
            outputs[kind] = (option, Path(path))
    for option, path in outputs.values():
        check_output(option, path)
    return outputs


def write_outputs(
    outputs: dict[str, tuple[str, Path]], *, document: Any, markdown: Callable[[], str]
) -> None:
    """Writes the files `report_outputs` named: the JSON ``document`` and the Markdown page
    ``markdown()`` (made only when asked for), each atomically, saying so on stderr."""
    from sim.experiments.report_files import write_json, write_markdown

    if "json" in outputs:
        print(f"wrote {write_json(outputs['json'][1], document, indent=2)}", file=sys.stderr)
    if "markdown" in outputs:
        print(f"wrote {write_markdown(outputs['markdown'][1], markdown())}", file=sys.stderr)


def add_recordings(
    parser: argparse.ArgumentParser, *, default: bool, each: str, folder: bool = False
) -> None:
    """``--recordings/--no-recordings``: one Rerun ``.rrd`` per ``each`` in OUT/recordings/
    (``folder``: the former ``--recordings DIR`` still works)."""
    parser.add_argument(
        "--recordings",
        action=_Recordings,
        default=default,
        folder=folder,
        help=f"write one Rerun .rrd per {each} in OUT/recordings/ (default: "
        f"{'yes' if default else 'no'})",
    )


def add_frames(
    parser: argparse.ArgumentParser,
    *,
    default: str | None = "all",
    scored: str,
    default_help: str = "every frame, annotated or not",
) -> None:
    """``--frames all|train|test`` and ``--train-fraction F``: which annotated frames are
    ``scored`` (``all``, or the part of `reform.time_split`); read by
    `sim.cli._common.select_frames` (``default`` None: every frame, annotated or not)."""
    parser.add_argument(
        "--frames",
        choices=FRAME_CHOICES,
        default=default,
        help=f"annotated frames {scored}: all, or the train/test part of reform.time_split "
        f"(default: {default or default_help})",
    )
    parser.add_argument(
        "--train-fraction",
        type=ascii_float,
        default=None,
        metavar="F",
        help="with --frames train|test: each sequence's share of annotated frames, by time, in "
        f"the train part (default {TRAIN_FRACTION:g})",
    )


def data_entries(
    values: Sequence[str] | None, names: Sequence[str]
) -> tuple[dict[str, str], list[str]]:
    """Splits ``--data`` values into ``NAME=PATH`` pairs for ``names`` and the rest (paths,
    dataset names, folders holding several datasets)."""
    named: dict[str, str] = {}
    rest: list[str] = []
    for value in values or ():
        name, sep, path = value.partition("=")
        if sep and name in names:
            named[name] = path
        else:
            rest.append(value)
    return named, rest


def add_temporal_arguments(parser: argparse.ArgumentParser) -> None:
    """``--temporal`` and ``--tolerance S``: score the detector's group events in time too."""
    parser.add_argument(
        "--temporal",
        action="store_true",
        help="also score the group events in time: recall and precision per kind, latency, "
        "false events per minute, identity switches (docs/guide/temporal.md)",
    )
    parser.add_argument(
        "--tolerance",
        type=ascii_float,
        default=None,
        metavar="S",
        help="with --temporal: seconds between a true event and the detected event matching "
        "it (default: 1 s, or the frame interval where frames come further apart)",
    )

"""What the ``experiment`` subcommands share: where SALSA and Babble are (``--data``), the
report each writes (DIR/NAME.md and DIR/NAME.json) and the command line it records."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import Any

from sim.cli._common import CliError, add_train_fraction_argument, check_output, warn_deprecated
from sim.cli._grammar import appender, data_entries, rename

REPORT_SUFFIXES = (".md", ".json")
DATA_HELP = (
    "a dataset (repeatable): NAME=PATH, a fetched or local dataset's name ({names}), its folder, "
    "or a folder holding {folders} (default: the fetched or local {names})"
)


def add_io_arguments(
    parser: argparse.ArgumentParser,
    *,
    basename: str,
    names: tuple[str, ...] = ("salsa", "babble"),
) -> None:
    """What an experiment reads and writes: ``--data`` naming the datasets ``names``
    (`add_dataset_arguments`) and ``--out DIR`` for its report (`add_out_argument`)."""
    add_dataset_arguments(parser, names=names)
    add_out_argument(parser, basename=basename)


def add_salsa_split_arguments(parser: argparse.ArgumentParser, *, basename: str, use: str) -> None:
    """What an experiment fitted on SALSA's time split reads and writes (`add_io_arguments`) and
    its ``--train-fraction``: the share of each SALSA session's annotated frames, by time, and
    ``use``, what that share is for (with its default)."""
    add_io_arguments(parser, basename=basename)
    add_train_fraction_argument(
        parser, help=f"share of each SALSA session's annotated frames, by time, {use}"
    )


def add_dataset_arguments(
    parser: argparse.ArgumentParser, *, names: tuple[str, ...] = ("salsa", "babble")
) -> None:
    """``--data`` (repeatable) naming the datasets ``names``; the former ``--datasets DIR``,
    ``--salsa PATH`` and ``--babble PATH`` are its old spellings."""
    parser.add_argument(
        "--data",
        action="append",
        default=[],
        metavar="PATH|NAME",
        help=DATA_HELP.format(names=", ".join(names), folders=" and ".join(f"{n}/" for n in names)),
    )
    rename(parser, "--datasets", "--data DIR", appender("data"), metavar="DIR")
    for name in names:
        rename(
            parser,
            f"--{name}",
            f"--data {name}=PATH",
            appender("data", lambda path, name=name: f"{name}={path}"),
            metavar="PATH",
        )


def named_datasets(
    args: argparse.Namespace, names: tuple[str, ...] = ("salsa", "babble")
) -> dict[str, str]:
    """Each of ``names`` as ``--data`` gives it: a path or a dataset's name, which the caller
    loads through `reform.datasets.resolve` (the name itself when ``--data`` says nothing of it:
    the fetched or local dataset). A path that does not say which dataset it is: `CliError`."""
    named, rest = data_entries(args.data, names)
    for value in rest:
        folder = Path(value)
        if value in names:
            named.setdefault(value, value)
        elif folder.name.lower() in names:
            named.setdefault(folder.name.lower(), value)
        elif folder.is_dir() and any((folder / name).is_dir() for name in names):
            for name in names:
                named.setdefault(name, str(folder / name))
        else:
            raise CliError(
                f"--data {value}: expected one of {', '.join(names)} (a name, NAME=PATH, its "
                f"folder or a folder holding {' and '.join(f'{n}/' for n in names)}), found "
                f"{'a folder holding none of them' if folder.is_dir() else 'nothing it names'}; "
                f"say which it is, e.g. --data {names[0]}={value}"
            )
    return {name: named.get(name, name) for name in names}


def dataset_locations(data: dict[str, str]) -> dict[str, Any]:
    """Where each dataset of `named_datasets` is (`reform.datasets.resolve`), before any is
    read: a path given for one that is not there, or that holds a dataset of another format
    (`reform.datasets.detect_format`; each name here is its format's), is a `CliError` saying
    what ``--data NAME=PATH`` takes and what it found. A public dataset's name that is not here
    is `resolve`'s error (how to fetch it); a path detection cannot tell is left to the loader."""
    from reform.datasets import DataFormatError, detect_format, registry, resolve
    from reform.datasets.detect import FORMAT_FILES

    locations = {}
    for name, value in data.items():
        try:
            locations[name] = resolve(value)
        except FileNotFoundError:
            if value in {dataset.name for dataset in registry()}:
                raise
            found = "no such file or folder"
        else:
            try:
                kind = detect_format(locations[name])
            except DataFormatError:  # none of the formats, or several: the loader says
                continue
            if kind == name:
                continue
            found = f"a dataset in the {kind} format"
        raise CliError(
            f"--data {name}={value}: expected {FORMAT_FILES[name]} (or a dataset's name), "
            f"found {found}"
        )
    return locations


def dataset_words(args: argparse.Namespace) -> list[str]:
    """The ``--data`` values given, as command-line words."""
    return [word for value in args.data for word in ("--data", value)]


def experiment_command(name: str, args: argparse.Namespace, options: list[str]) -> str:
    """The command line an experiment's report records: ``reform-sim experiment NAME``, the
    ``--data`` given, ``options`` (the words of the options that differ from their defaults)
    and ``--out``."""
    return shlex.join(
        ["reform-sim", "experiment", name, *dataset_words(args), *options, "--out", args.out]
    )


def add_out_argument(parser: argparse.ArgumentParser, *, basename: str) -> None:
    """The required ``--out DIR``: the folder of BASENAME.md and BASENAME.json."""
    parser.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help=f"folder for {basename}.md and {basename}.json (created)",
    )


def report_stem(out: str, basename: str, *, suffixes: tuple[str, ...] = REPORT_SUFFIXES) -> Path:
    """Where ``--out`` puts the report, without its extension: DIR/BASENAME. The former
    spelling, a path ending in one of ``suffixes``, still names the files themselves (with a
    warning naming the new one)."""
    path = Path(out)
    if path.suffix in suffixes:
        warn_deprecated(
            f"--out {out} (a file name)",
            f"--out {path.parent} (a folder: {path.parent / basename}.md and .json)",
        )
        return path.with_suffix("")
    return path / basename


def report_target(out: str, basename: str) -> Path:
    """Where ``--out`` puts the report (`report_stem`), checked writable up front
    (`check_report`): DIR/BASENAME, without its extension."""
    stem = report_stem(out, basename)
    check_report(stem)
    return stem


def check_report(
    stem: Path, *, suffixes: tuple[str, ...] = REPORT_SUFFIXES, option: str = "--out"
) -> None:
    """Raises `CliError` unless STEM.md, STEM.json (``suffixes``) can be written: up front,
    before the experiment runs."""
    check_output(option, stem.parent, folder=True)
    for suffix in suffixes:
        check_output(option, stem.with_name(stem.name + suffix))


def publish(markdown: str, document: dict[str, Any], *, stem: Path) -> None:
    """Writes an experiment's report (its page and its JSON) to STEM.md and STEM.json and
    prints the Markdown."""
    write_report(stem, markdown, document)
    print(markdown, end="")
    print(f"wrote {stem}.md and {stem}.json", file=sys.stderr)


def write_report(stem: Path, markdown: str, document: dict[str, Any], *, indent: int = 2) -> None:
    """Writes ``STEM.md`` and ``STEM.json`` (atomically; missing folders are created)."""
    from sim.experiments.report_files import write_json, write_markdown

    write_markdown(stem.with_name(stem.name + ".md"), markdown)
    write_json(stem.with_name(stem.name + ".json"), document, indent=indent)

"""What the ``experiment`` subcommands share: where SALSA and Babble are, and the report each
writes (OUT.md and OUT.json)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from sim.cli._common import CliError, check_output

OUT_HELP = "output path without extension: writes OUT.md and OUT.json"
REPORT_SUFFIXES = (".md", ".json")


def add_dataset_arguments(parser: argparse.ArgumentParser, *, babble: bool = True) -> None:
    """``--datasets DIR``, ``--salsa PATH|NAME`` and, with ``babble``, ``--babble PATH|NAME``."""
    held = "salsa/ and babble/" if babble else "salsa/"
    parser.add_argument(
        "--datasets", metavar="DIR", help=f"folder holding {held} (e.g. ../shared/datasets)"
    )
    parser.add_argument(
        "--salsa",
        metavar="PATH|NAME",
        help="SALSA folder or dataset name (default: DIR/salsa, else the fetched or local salsa)",
    )
    if babble:
        parser.add_argument(
            "--babble",
            metavar="PATH|NAME",
            help="Babble folder or dataset name (default: DIR/babble, else the fetched or local "
            "babble)",
        )


def salsa_and_babble(args: argparse.Namespace) -> tuple[str, str]:
    """The SALSA and Babble folders: ``--salsa`` / ``--babble``, else under ``--datasets``.

    ``--salsa`` and ``--babble`` may name a dataset (a fetched one, or a folder of the real
    datasets'): the caller loads them through `reform.datasets.resolve`, after checking its
    outputs."""
    salsa = args.salsa or (args.datasets and str(Path(args.datasets) / "salsa"))
    babble = args.babble or (args.datasets and str(Path(args.datasets) / "babble"))
    if not salsa or not babble:
        raise CliError(
            "give --datasets DIR (holding salsa/ and babble/) or --salsa and --babble (paths, or "
            "the names of fetched datasets: reform-sim datasets fetch salsa babble)"
        )
    return salsa, babble


def dataset_words(args: argparse.Namespace) -> list[str]:
    """The dataset flags of :func:`add_dataset_arguments` given, as command-line words."""
    words = ["--datasets", args.datasets] if args.datasets else []
    for flag, value in (("--salsa", args.salsa), ("--babble", args.babble)):
        if value:
            words += [flag, value]
    return words


def add_out_argument(parser: argparse.ArgumentParser, *, help: str = OUT_HELP) -> None:  # noqa: A002
    """The required ``--out OUT``."""
    parser.add_argument("--out", required=True, metavar="OUT", help=help)


def report_stem(out: str, *, suffixes: tuple[str, ...] = REPORT_SUFFIXES) -> Path:
    """``--out`` without its extension when it is one of ``suffixes``."""
    path = Path(out)
    return path.with_suffix("") if path.suffix in suffixes else path


def check_report(
    stem: Path, *, suffixes: tuple[str, ...] = REPORT_SUFFIXES, option: str = "--out"
) -> None:
    """Raises `CliError` unless STEM.md, STEM.json (``suffixes``) can be written: up front,
    before the experiment runs."""
    for suffix in suffixes:
        check_output(option, stem.with_name(stem.name + suffix))


def publish(markdown: str, document: dict[str, Any], *, out: str) -> None:
    """Writes an experiment's report (its page and its JSON) to OUT.md and OUT.json and prints
    the Markdown."""
    stem = report_stem(out)
    write_report(stem, markdown, document)
    print(markdown, end="")
    print(f"wrote {stem}.md and {stem}.json", file=sys.stderr)


def write_report(stem: Path, markdown: str, document: dict[str, Any], *, indent: int = 2) -> None:
    """Writes ``STEM.md`` and ``STEM.json`` (atomically; missing folders are created)."""
    from reform.atomic import atomic_open

    with atomic_open(stem.with_name(stem.name + ".md")) as handle:
        handle.write(markdown)
    with atomic_open(stem.with_name(stem.name + ".json")) as handle:
        json.dump(document, handle, indent=indent, allow_nan=False)
        handle.write("\n")

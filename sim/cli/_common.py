"""Pieces the subcommands share."""

from __future__ import annotations

import argparse

FORMATS = ("salsa", "babble", "gcff", "parquet")


class CliError(Exception):
    """A user-facing error: printed as one line by ``reform-sim``, exit status 2."""


def add_data_arguments(parser: argparse.ArgumentParser, *, flag: str = "--data") -> None:
    """``--data PATH [--format F] [--units cm|m]``: where a dataset is and how to read it."""
    parser.add_argument(flag, required=True, metavar="PATH", help="dataset file or folder")
    parser.add_argument(
        "--format",
        choices=FORMATS,
        default=None,
        help="dataset format (default: detected from the path)",
    )
    parser.add_argument(
        "--units",
        choices=("cm", "m"),
        default=None,
        help="length unit of the file's positions (GCFF folders: default cm; others fixed)",
    )


def load_data(args: argparse.Namespace, *, attribute: str = "data"):
    """Loads the dataset named by :func:`add_data_arguments`."""
    from reform.datasets import load_dataset

    return load_dataset(getattr(args, attribute), format=args.format, units=args.units)

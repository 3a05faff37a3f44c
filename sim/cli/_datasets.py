"""``reform-sim datasets``: the field's public datasets: list them, fetch them into the cache."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from sim.cli._common import CliError

_DESCRIPTION = """\
The field's public F-formation datasets (CoffeeBreak, Cocktail Party, Synth, GDet, SALSA,
Babble), each pinned to a commit of its public repository with every file's size and sha256.
`fetch` downloads them, verified, into the cache ($REFORM_SIM_DATA, else the platform's user
data folder); every command's --data then takes a fetched dataset's name. `reform-sim datasets`
alone is `reform-sim datasets list`.
"""

_FETCH_DESCRIPTION = """\
Downloads every file of each dataset named at the commit the registry pins, checks its size and
sha256, and keeps it in the cache; a dataset already there, complete and verified, is not
downloaded again. Prints each dataset's folder, ready for --data (or its name). --mirror fetches
from a mirror laid out as <mirror>/<repo>/<commit>/<path> (an http://, https:// or file:// URL,
or a folder), for machines without access to GitHub.
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "datasets",
        help="list or fetch the field's public datasets",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_actions,
    )


def _common_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--cache",
        metavar="DIR",
        default=None,
        help="the cache folder (default: $REFORM_SIM_DATA, else the user data folder)",
    )
    parser.add_argument(
        "--registry",
        metavar="FILE",
        default=None,
        help="another registry file, laid out as the packaged public-datasets.json",
    )


def _actions(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="action", metavar="ACTION")
    parser.set_defaults(handler=run_list, cache=None, registry=None, json=False)
    actions.add_parser(
        "list",
        help="name, title, format, size, licence note, and where it is on this machine",
        description=(
            "Lists the public datasets: name, title, format, size, licence note, and whether "
            "each is fetched on this machine (and where)."
        ),
        arguments=_list_arguments,
    )
    actions.add_parser(
        "fetch",
        help="download datasets into the cache, verified",
        description=_FETCH_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        arguments=_fetch_arguments,
    )


def _list_arguments(parser: argparse.ArgumentParser) -> None:
    _common_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.set_defaults(handler=run_list)


def _fetch_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("names", nargs="*", metavar="NAME", help="datasets to fetch")
    parser.add_argument("--all", action="store_true", help="fetch every public dataset")
    parser.add_argument(
        "--mirror",
        metavar="URL",
        default=None,
        help="fetch from <URL>/<repo>/<commit>/<path> (http://, https://, file:// or a folder)",
    )
    _common_arguments(parser)
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bars (shown on a terminal only)"
    )
    parser.set_defaults(handler=run_fetch)


def format_size(n_bytes: int) -> str:
    """``n_bytes`` in decimal units: ``"226 B"``, ``"32.4 kB"``, ``"2.9 MB"``."""
    if n_bytes < 1000:
        return f"{n_bytes} B"
    for unit in ("kB", "MB", "GB"):
        n_bytes /= 1000
        if n_bytes < 1000 or unit == "GB":
            return f"{n_bytes:.1f} {unit}"
    raise AssertionError("unreachable")  # pragma: no cover


def _rows(args: argparse.Namespace) -> tuple[Path, list[dict[str, Any]]]:
    from reform.datasets import cache_dir, is_fetched, local_datasets_dir, registry

    cache = Path(args.cache) if args.cache is not None else cache_dir()
    local = local_datasets_dir()
    rows = []
    for dataset in registry(args.registry):
        fetched = is_fetched(dataset.name, cache, registry=args.registry)
        here = local / dataset.name if local is not None else None
        rows.append(
            {
                "name": dataset.name,
                "title": dataset.title,
                "format": dataset.format,
                "units": dataset.units,
                "bytes": dataset.bytes,
                "files": len(dataset.files),
                "licence": dataset.licence,
                "repo": dataset.repo,
                "citation": dataset.citation,
                "fetched": fetched,
                "path": str(cache / dataset.name) if fetched else None,
                "local": str(here) if here is not None and here.is_dir() else None,
            }
        )
    return cache, rows


def run_list(args: argparse.Namespace) -> int:
    cache, rows = _rows(args)
    if args.json:
        json.dump({"cache": str(cache), "datasets": rows}, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    print(format_table(rows, cache=cache), end="")
    return 0


def format_table(rows: list[dict[str, Any]], *, cache: Path) -> str:
    """The datasets as an aligned table, the cache folder above it."""
    header = ("name", "title", "format", "size", "licence", "on this machine")
    table = [header] + [
        (
            row["name"],
            row["title"],
            row["format"],
            format_size(row["bytes"]),
            row["licence"] or "-",
            f"fetched, {row['path']}"
            if row["fetched"]
            else f"in {row['local']}"
            if row.get("local")
            else "no",
        )
        for row in rows
    ]
    widths = [max(len(line[k]) for line in table) for k in range(len(header) - 1)]
    lines = [f"cache: {cache} (set $REFORM_SIM_DATA or --cache to change)"]
    for line in table:
        cells = [cell.ljust(width) for cell, width in zip(line, widths, strict=False)]
        lines.append("  ".join([*cells, line[-1]]))
    return "\n".join(lines) + "\n"


def run_fetch(args: argparse.Namespace) -> int:
    from reform.datasets import cache_dir, fetch, is_fetched, registry

    known = [dataset.name for dataset in registry(args.registry)]
    if args.all and args.names:
        raise CliError("give dataset names or --all, not both")
    if not args.all and not args.names:
        raise CliError(f"give dataset names or --all; the public datasets are: {', '.join(known)}")
    names = known if args.all else list(dict.fromkeys(args.names))
    unknown = [name for name in names if name not in known]
    if unknown:
        raise CliError(
            f"unknown dataset {unknown[0]!r}; the public datasets are: {', '.join(known)}"
        )
    cache = args.cache if args.cache is not None else cache_dir()
    for name in names:
        already = is_fetched(name, cache, registry=args.registry)
        folder = fetch(
            name,
            mirror=args.mirror,
            cache=cache,
            progress=not args.no_progress and sys.stderr.isatty(),
            registry=args.registry,
        )
        print(f"{name}: {folder}" + (" (already fetched)" if already else ""))
    return 0

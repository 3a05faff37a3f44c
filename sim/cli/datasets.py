"""What ``reform-sim datasets`` does when it runs.

Its arguments are `sim.cli._datasets`."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from reform.datasets import cache_dir, fetch, is_fetched, local_datasets_dir, registry
from sim.cli._common import CliError


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
            progress=not args.quiet and sys.stderr.isatty(),
            registry=args.registry,
        )
        print(f"{name}: {folder}" + (" (already fetched)" if already else ""))
    return 0

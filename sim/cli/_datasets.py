"""``reform-sim datasets``: the field's public datasets: list them, fetch them into the cache."""

from __future__ import annotations

import argparse

from sim.cli._common import Action, add_actions, run_with
from sim.cli._grammar import add_quiet

DESCRIPTION = """\
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


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_actions(parser, ACTIONS, required=False)  # no action: list
    parser.set_defaults(
        handler=run_with("sim.cli.datasets:run_list"), cache=None, registry=None, json=False
    )


def _list_arguments(parser: argparse.ArgumentParser) -> None:
    _common_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.set_defaults(handler=run_with("sim.cli.datasets:run_list"))


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
    add_quiet(parser)
    parser.set_defaults(handler=run_with("sim.cli.datasets:run_fetch"))


ACTIONS = (
    Action(
        "list",
        "name, title, format, size, licence note, and where it is on this machine",
        "Lists the public datasets: name, title, format, size, licence note, and whether each is "
        "fetched on this machine (and where).",
        _list_arguments,
        as_written=False,
    ),
    Action(
        "fetch",
        "download datasets into the cache, verified",
        _FETCH_DESCRIPTION,
        _fetch_arguments,
    ),
)

"""``reform-sim scenarios``: the registered scenarios, what they are and their typed options."""

from __future__ import annotations

import argparse
import json


def register(subparsers: argparse._SubParsersAction) -> None:
    subparsers.add_parser(
        "scenarios",
        help="list the registered scenarios and their options",
        description=(
            "Lists the registered scenarios with a line on each and their options (name, type, "
            "default, meaning). Set options with `reform-sim simulate --set KEY=VALUE`."
        ),
        arguments=_arguments,
    )


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("names", nargs="*", metavar="NAME", help="only these scenarios")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")
    parser.set_defaults(handler=run)


def _json_default(value):
    return value if isinstance(value, (bool, int, float, str)) or value is None else str(value)


def run(args: argparse.Namespace) -> int:
    import scenarios

    infos = [scenarios.describe(n) for n in (args.names or scenarios.names())]
    if args.json:
        document = [
            {
                "name": info.name,
                "description": info.description,
                "options": [
                    {
                        "name": o.name,
                        "type": o.type.__name__,
                        "choices": list(o.choices) if o.choices else None,
                        "default": _json_default(o.default),
                        "help": o.help,
                    }
                    for o in info.options
                ],
            }
            for info in infos
        ]
        print(json.dumps(document, indent=2))
        return 0
    blocks = []
    for info in infos:
        lines = [f"{info.name}: {info.description}"]
        width = max((len(o.name) for o in info.options), default=0)
        type_width = max((len(o.type_name) for o in info.options), default=0)
        for o in info.options:
            default = repr(o.default) if isinstance(o.default, str) else f"{o.default}"
            lines.append(
                f"  {o.name:<{width}}  {o.type_name:<{type_width}}  = {default:<8}  {o.help}"
            )
        blocks.append("\n".join(lines))
    print("\n\n".join(blocks))
    return 0

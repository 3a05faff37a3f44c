"""What ``reform-sim scenarios`` does when it runs.

Its arguments are `sim.cli._scenarios`."""

from __future__ import annotations

import argparse
import json

import scenarios


def _json_default(value):
    return value if isinstance(value, (bool, int, float, str)) or value is None else str(value)


def run(args: argparse.Namespace) -> int:
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

"""MkDocs hook: the reference pages, generated at build time from the code itself.

* ``reference/cli.md``: every ``reform-sim`` subcommand, walked from the parser that the command
  builds (`sim.cli.build_parser`, each subcommand's arguments from ``sim/cli/_NAME.py``), so the
  page cannot drift from ``--help``.
* ``detectors/catalogue.md``: the detector catalogue (`reform.catalogue`), every name with what it
  is, its options as declared (type, unit, range, default), what it needs and its citation, so
  the page cannot drift from ``--help`` either.
* ``reference/api/PACKAGE.md``: one mkdocstrings entry per public name of each package's
  ``__all__``, pointed at the module that defines it (the packages load their names lazily,
  which a static reader cannot follow).
"""

from __future__ import annotations

import argparse
import importlib
import inspect

from mkdocs.structure.files import File, Files

# Package -> the sentence that opens its page.
API_PACKAGES = {
    "reform": "The science: frames, detectors (REFORM, GCFF), features, the evaluation "
    "protocol, persistence.",
    "reform.datasets": "Loaders of the field's datasets, the project's Parquet format and the "
    "public datasets' cache.",
    "scenarios": "Scripted social scenes, registered by name.",
    "sim": "The simulator core: MuJoCo scenes, the world, the robot's sensor and camera.",
    "sim.envs": "Gymnasium environments: the Directions Robot as the agent.",
}


def on_files(files: Files, config) -> Files:
    files.append(File.generated(config, "reference/cli.md", content=cli_markdown()))
    files.append(File.generated(config, "detectors/catalogue.md", content=catalogue_markdown()))
    for package in API_PACKAGES:
        files.append(
            File.generated(config, f"reference/api/{package}.md", content=api_markdown(package))
        )
    return files


# --- the detector catalogue ----------------------------------------------------------------------

_NEEDS = {
    "": "nothing",
    "dataset": "the dataset it runs on",
    "training": "annotated training frames",
}


def catalogue_markdown() -> str:
    from pathlib import Path

    from reform.detectors import builtin_names, detector_info, detector_names

    pages = Path(__file__).resolve().parents[1] / "detectors"
    lines = [
        "# The detector catalogue",
        "",
        "Every detector the project ships, by the one name each command knows it by "
        "(`--detector NAME` of `evaluate`, `detect`, `benchmark`, `stress`, `tune`; "
        "`reform.make_detector(NAME, **options)`), generated from the catalogue "
        "(`reform/catalogue.py`) when this site is built. Options are set with `--option "
        "NAME=VALUE` or a settings file (`--settings FILE.json`) and checked against the "
        "range below; `benchmark --detector all` and `stress --detector all` run every "
        "detector that needs no model file (" + ", ".join(f"`{n}`" for n in builtin_names()) + ").",
        "",
        "| name | what it is | options | needs before it predicts | paper |",
        "|---|---|---|---|---|",
    ]
    for name in detector_names():
        info = detector_info(name)
        if info.source != "built-in":
            continue
        page = pages / f"{name}.md"
        shown = f"[`{name}`]({name}.md)" if page.is_file() else f"`{name}`"
        options = "<br>".join(_cell(o.describe()) for o in info.options) or "none"
        lines.append(
            f"| {shown} | {_cell(info.help)} | {options} | {_NEEDS[info.needs]} | "
            f"{_cell(info.citation) or '–'} |"
        )
    lines += [
        "",
        "Your own detector joins the catalogue with one `register_detector` call (or an entry "
        "point), its options declared the same way: see [Adding a detector]"
        "(../guide/extending.md).",
        "",
    ]
    return "\n".join(lines)


# --- the command line ---------------------------------------------------------------------------


def cli_markdown() -> str:
    from sim.cli import COMMANDS, build_parser

    parser = build_parser()
    lines = [
        "# Command reference",
        "",
        "Every subcommand of `reform-sim`, generated from the parsers the command builds when "
        "this site is built: what `reform-sim COMMAND --help` prints, laid out as tables. The "
        "[guides](../guide/architecture.md) explain what the commands are for.",
        "",
        "| command | what it does |",
        "|---|---|",
    ]
    for command in COMMANDS:
        lines.append(f"| [`{command.name}`](#reform-sim-{command.name}) | {_cell(command.help)} |")
    lines += ["", "## One grammar", "", *_grammar_table()]
    lines += ["", "## `reform-sim`", "", _usage(parser), ""]
    lines += _options(parser)
    lines += _subcommands(parser, "reform-sim", level=2)
    return "\n".join(lines) + "\n"


def _grammar_table() -> list[str]:
    """The grammar every subcommand keeps, as `sim.cli._grammar` states it (its table, each
    concept and its one spelling), and the old spellings that still work."""
    from sim.cli import _grammar

    text = _grammar.__doc__
    intro, table, outro = text.split("\n=")[0], text.split("=\n")[1], text.split("=\n")[-1]
    rows: list[list[str]] = []
    for line in table.splitlines():
        if line.startswith("="):
            break
        concept, spelling = line[:19].strip(), line[19:].strip()
        if concept:
            rows.append([concept, spelling])
        else:
            rows[-1][1] += " " + spelling
    lines = [_rst(" ".join(intro.split()[intro.split().index("Each") :])), ""]
    lines += ["| concept | spelling |", "|---|---|"]
    # Python-Markdown's tables keep a pipe inside a code span as it is: no escape.
    lines += [f"| {concept} | {_rst(spelling)} |" for concept, spelling in rows]
    return [*lines, "", _rst(" ".join(outro.split()))]


def _rst(text: str) -> str:
    """reStructuredText literals (````x````) and references (`` `x` ``) as Markdown code spans,
    the text between them shown as it is (`_text`)."""
    parts = text.replace("``", "`").split("`")
    return "`".join(part if k % 2 else _text(part) for k, part in enumerate(parts))


def _subcommands(parser: argparse.ArgumentParser, prog: str, *, level: int) -> list[str]:
    lines: list[str] = []
    for action in parser._actions:
        if not isinstance(action, argparse._SubParsersAction):
            continue
        helps = {choice.dest: choice.help for choice in action._choices_actions}
        seen: set[int] = set()
        for name, sub in action.choices.items():
            if id(sub) in seen:  # an alias of a subcommand already written
                continue
            seen.add(id(sub))
            sub.format_help()  # adds the subcommand's arguments (they are added on first use)
            full = f"{prog} {name}"
            aliases = [n for n, p in action.choices.items() if p is sub and n != name]
            lines += ["", f"{'#' * level} `{full}` {{#{full.replace(' ', '-')}}}", ""]
            if helps.get(name):
                lines += [f"*{_text(helps[name])}*", ""]
            if aliases:
                lines += ["Also: " + ", ".join(f"`{prog} {a}`" for a in aliases) + ".", ""]
            if sub.description:
                lines += [_text(" ".join(sub.description.split())), ""]
            lines += [_usage(sub), ""]
            lines += _options(sub)
            lines += _subcommands(sub, full, level=min(level + 1, 6))
    return lines


def _usage(parser: argparse.ArgumentParser) -> str:
    return "```text\n" + parser.format_usage().strip() + "\n```"


def _options(parser: argparse.ArgumentParser) -> list[str]:
    lines: list[str] = []
    for group in parser._action_groups:
        rows = []
        for action in group._group_actions:
            if action.help == argparse.SUPPRESS or isinstance(
                action, argparse._SubParsersAction | argparse._HelpAction
            ):
                continue
            rows.append(f"| {_flags(action)} | {_help(action)} | {_default(action)} |")
        if rows:
            title = group.title or "options"
            lines += [f"**{title[0].upper() + title[1:]}**", ""]
            if group.description:
                lines += [_text(" ".join(group.description.split())), ""]
            lines += ["| argument | meaning | default |"]
            lines += ["|---|---|---|", *rows, ""]
    return lines


def _flags(action: argparse.Action) -> str:
    if not action.option_strings:
        return f"`{_metavar(action)}`"  # a pipe inside a code span does not split the cell
    takes_value = action.nargs != 0
    metavar = f" {_metavar(action)}" if takes_value else ""
    return "<br>".join(f"`{flag}{metavar}`" for flag in action.option_strings)


def _metavar(action: argparse.Action) -> str:
    if isinstance(action.metavar, tuple):
        return " ".join(action.metavar)
    if action.metavar is not None:
        return action.metavar
    if action.choices is not None:
        return "{" + ",".join(map(str, action.choices)) + "}"
    return action.dest.upper() if action.option_strings else action.dest


def _help(action: argparse.Action) -> str:
    text = action.help or ""
    if "%" in text:
        params = {k: v for k, v in vars(action).items() if v is not argparse.SUPPRESS}
        for key, value in list(params.items()):
            if isinstance(value, list | tuple) and key == "choices":
                params[key] = ", ".join(map(str, value))
        params["prog"] = ""
        try:
            text = text % params
        except (KeyError, TypeError, ValueError):
            pass
    required = getattr(action, "required", False) and action.option_strings
    return ("**required.** " if required else "") + _cell(text)


def _default(action: argparse.Action) -> str:
    default = action.default
    if (
        default is None
        or default is argparse.SUPPRESS
        or action.nargs == 0
        or default == []
        or callable(default)
    ):
        return ""
    return f"`{default}`"


def _cell(text: str) -> str:
    return _text(" ".join(str(text).split())).replace("|", "\\|")


def _text(text: str) -> str:
    """Plain help text as Markdown: angle brackets and stars shown as they are."""
    return (
        text.replace("&", "&amp;")
        .replace("<", "&lt;")
        .replace(">", "&gt;")
        .replace("*", "\\*")
        .replace("_", "\\_")
    )


# --- the Python API -----------------------------------------------------------------------------


def api_markdown(package: str) -> str:
    module = importlib.import_module(package)
    exports = getattr(module, "_EXPORTS", {})
    lines = [
        f"# `{package}`",
        "",
        API_PACKAGES[package],
        "",
        f"Every public name of `{package}` (its `__all__`), as `from {package} import NAME` "
        "gives it, documented from its docstring.",
        "",
    ]
    elsewhere = []
    for name in module.__all__:
        if name.startswith("__"):
            continue
        target = f"{_defined_in(module, exports, name)}.{name}"
        owner = _owner(target)
        if owner != package:  # documented on the page of the package that defines it
            elsewhere.append(f"- [`{package}.{name}`][{target}]: on the `{owner}` page")
            continue
        lines += [f"::: {target}", "    options:", f'      heading: "{package}.{name}"', ""]
    if elsewhere:
        lines += ["## Also exported here", "", *elsewhere, ""]
    return "\n".join(lines)


def _owner(target: str) -> str:
    """The package of `API_PACKAGES` whose page documents ``target``: the closest enclosing."""
    enclosing = [p for p in API_PACKAGES if target.startswith(p + ".")]
    return max(enclosing, key=len)


def _defined_in(module, exports: dict[str, str], name: str) -> str:
    if name in exports:
        return exports[name]
    obj = getattr(module, name)
    if inspect.isclass(obj) or inspect.isfunction(obj):
        return obj.__module__
    return module.__name__

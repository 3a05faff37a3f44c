"""Every ``reform-sim`` command the README and the documentation show parses as written: its
subcommand exists, its flags are the command's (no old spelling), its values fit their types.

Runs no command (the tutorials' blocks run in test_tutorials.py, slowly); it catches a page left
behind by a renamed flag, a changed metavar or a removed subcommand, by parsing alone."""

from __future__ import annotations

import re
import shlex

import pytest
from site_pages import DOCS, blocks

from sim.cli import build_parser

REPO = DOCS.parent
PARSER = build_parser()  # one parser for every case: argparse parses again from scratch
# The README and every page but the results', whose commands are the records of past runs.
PAGES = [REPO / "README.md", *sorted(p for p in DOCS.rglob("*.md") if p.parent.name != "results")]
# Words that mark a line as a pattern rather than a command (alternatives, elisions, prompts).
PLACEHOLDER = re.compile(r"\.\.\.|…|<[A-Za-z]|\|(?!\|)|\[--|\bNAME\b(?!=)|\$\w")


def _commands(text: str) -> list[tuple[int, str, bool]]:
    """(line, command, whole) of each ``reform-sim`` command of a page: in a code block, whole
    (a continuation line with ``\\`` joined, a ``$`` prompt dropped), or inline in the text,
    perhaps a fragment (``reform-sim generate --twin``) whose other flags the text leaves out."""
    found = []
    for block in blocks(text):
        if block.title is not None:
            continue
        lines = block.code.split("\n")
        k = 0
        while k < len(lines):
            start, line = k, lines[k]
            while line.rstrip().endswith("\\") and k + 1 < len(lines):
                k += 1
                line = line.rstrip()[:-1] + " " + lines[k].strip()
            k += 1
            line = line.strip().removeprefix("$ ")
            answer = lines[k].strip() if k < len(lines) else ""
            if re.match(r"reform-sim [\w ]+: error:", answer):
                continue  # bad input shown with its refusal (docs/bad-input.md)
            if line.startswith("reform-sim "):
                found.append((block.line + 1 + start, line, True))
    for n, line in enumerate(text.split("\n"), start=1):
        found += [(n, m, False) for m in re.findall(r"`(reform-sim [^`]+)`", line)]
    return found


def _words(command: str) -> list[str] | None:
    """The command's words after ``reform-sim``, or None when it is a pattern or a pipeline."""
    command = re.split(r"\s+#", command)[0]
    for stop in (" | ", " && ", " > ", " 2>", "; "):
        command = command.split(stop)[0]
    if PLACEHOLDER.search(command) or re.match(r"reform-sim [\w ]+: ", command):
        return None  # a pattern, or an error message quoted
    try:
        return shlex.split(command)[1:]
    except ValueError:
        return None


DOCUMENTED = [
    pytest.param(
        words,
        whole,
        "register_detector(" in page.read_text(encoding="utf-8"),
        id=f"{page.relative_to(REPO)}:{line}",
    )
    for page in PAGES
    for line, command, whole in _commands(page.read_text(encoding="utf-8"))
    if (words := _words(command))
]


def test_the_pages_show_commands():
    readme = [p for p in DOCUMENTED if p.id.startswith("README.md:")]
    assert len(readme) >= 8 and len(DOCUMENTED) >= 100, (len(readme), len(DOCUMENTED))


@pytest.mark.parametrize(("words", "whole", "registers"), DOCUMENTED)
def test_a_documented_command_parses_as_written(words, whole, registers, capsys):
    try:
        PARSER.parse_args(words)
    except SystemExit as stop:
        err = capsys.readouterr().err
        # A fragment in the text leaves flags out; a page that registers a detector uses it.
        fragment = not whole and re.search("arguments are required|expected one argument", err)
        own = registers and "argument --detector: invalid choice" in err
        assert stop.code == 0 or fragment or own, err  # --help, --version: exit 0
    err = capsys.readouterr().err
    assert "is deprecated" not in err, err

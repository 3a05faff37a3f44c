"""Every ``reform-sim`` command the README and the documentation show parses as written: its
subcommand exists, its flags are the command's (no old spelling), its values fit their types.

Runs no command (the tutorials' blocks run in test_tutorials.py, slowly); it catches a page left
behind by a renamed flag, a changed metavar or a removed subcommand, by parsing alone."""

from __future__ import annotations

import re

import pytest
from site_pages import COMMAND_PAGES, REPO, command_words, commands

from sim.cli import build_parser

PARSER = build_parser()  # one parser for every case: argparse parses again from scratch

DOCUMENTED = [
    pytest.param(
        words,
        command.whole,
        "register_detector(" in page.read_text(encoding="utf-8"),
        id=f"{page.relative_to(REPO)}:{command.line}",
    )
    for page in COMMAND_PAGES
    for command in commands(page.read_text(encoding="utf-8"))
    if command.refusal is None and (words := command_words(command.text))
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

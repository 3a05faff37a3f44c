"""``reform-sim --help`` and ``--version`` answered without building the parser.

The top-level help is what argparse formats from the command table, and nothing else: the same
text for the same code, Python, terminal width, colour setting and language. The first
``--help`` formats it with argparse (`sim.cli._main.build_parser`) and keeps it beside this
package's bytecode (``__pycache__``, or under ``PYTHONPYCACHEPREFIX``; nothing is kept when
Python writes no bytecode, ``PYTHONDONTWRITEBYTECODE``), its first line the key it was made
for; later ones print it when the key is the same, and format it afresh otherwise. The key names
the version, Python's build, the size and modification time of the modules that shape the help,
the terminal's width (``COLUMNS`` or the terminal's own), whether stdout is a terminal, and the
variables that set argparse's colours and language.

Light on purpose: it imports nothing Python has not loaded at start, so that ``--help`` answers
in about the time Python takes to start (issue 31; ``benchmarks/bench_cli_startup.py``).
"""

from __future__ import annotations

import os
import sys

# Modules whose text shapes the top-level help: the command table, the parser, its class.
_SOURCES = ("__init__.py", "_main.py", "_common.py", "_command.py")
# Variables argparse's output depends on beyond the width: its colours and its language.
_VARIABLES = (
    "COLUMNS",
    "NO_COLOR",
    "FORCE_COLOR",
    "PYTHON_COLORS",
    "TERM",
    "LANGUAGE",
    "LC_ALL",
    "LC_MESSAGES",
    "LANG",
)


def answer(flag: str) -> int:
    """Prints what ``reform-sim FLAG`` prints (``-h``, ``--help`` or ``--version``); returns
    the exit status."""
    if flag == "--version":
        from reform import __version__

        text = f"reform-sim {__version__}\n"
    else:
        key = _key()
        path = _path(key)
        text = _read(path, key)
        if text is None:
            from sim.cli._main import build_parser

            text = build_parser().format_help()
            _keep(path, key, text)
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:  # the reader left (`reform-sim --help | head -3`): done
        from sim.cli._main import _drop_stdout

        _drop_stdout()
    return 0


def _key() -> str:
    """What the top-level help is made from, on one line."""
    from reform import __version__

    here = os.path.dirname(os.path.abspath(__file__))
    sources = []
    for name in _SOURCES:
        try:
            stat = os.stat(os.path.join(here, name))
        except OSError:
            sources.append((name, None))
        else:
            sources.append((name, stat.st_size, stat.st_mtime_ns))
    try:
        stdout = sys.__stdout__.fileno()
        terminal = (os.isatty(stdout), os.get_terminal_size(stdout).columns)
    except (AttributeError, ValueError, OSError):
        terminal = (False, None)
    variables = tuple(os.environ.get(name) for name in _VARIABLES)
    return repr((__version__, sys.version, sources, terminal, variables))


def _path(key: str) -> str:
    """Where the help made for ``key`` is kept: beside this package's bytecode."""
    here = os.path.dirname(os.path.abspath(__file__))
    if sys.pycache_prefix:
        folder = os.path.join(sys.pycache_prefix, os.path.splitdrive(here)[1].lstrip(os.sep))
    else:
        folder = os.path.join(here, "__pycache__")
    return os.path.join(folder, f"help.{_fnv1a(key.encode()):016x}.txt")


def _read(path: str, key: str) -> str | None:
    """The help kept at ``path`` when it was made for ``key``, else None."""
    try:
        with open(path, encoding="utf-8") as file:
            kept_key, _, text = file.read().partition("\n")
    except (OSError, UnicodeDecodeError):
        return None
    return text if kept_key == key and text else None


def _keep(path: str, key: str, text: str) -> None:
    """Keeps ``text`` at ``path`` for ``key``, whole or not at all; nothing when Python writes no
    bytecode or the folder is not writable (the help is then formatted each time)."""
    if sys.dont_write_bytecode:
        return
    temporary = f"{path}.{os.getpid()}.tmp"
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(temporary, "w", encoding="utf-8") as file:
            file.write(f"{key}\n{text}")
        os.replace(temporary, path)
    except OSError:
        try:
            os.remove(temporary)
        except OSError:
            pass


def _fnv1a(data: bytes) -> int:
    """The 64-bit FNV-1a hash of ``data``: a file name for a key, stable across runs (``hash``
    is not) and importing nothing (the key itself, in the file, is what is checked)."""
    value = 0xCBF29CE484222325
    for byte in data:
        value = ((value ^ byte) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return value

"""``reform-sim --help`` and ``--version`` answer without argparse (`sim.cli._help_cache`): the
same text argparse formats, kept beside the bytecode for the same code, Python, width and
language, and formatted afresh when any of them differs."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from sim.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[3]
CONSOLE = "import sys; from sim.cli import console_main; sys.exit(console_main())"


def _console(
    *argv: str, prefix: Path, columns: int = 80, **env: str
) -> subprocess.CompletedProcess:
    """``reform-sim ARGV`` as the console command runs, its bytecode (and the kept help) under
    ``prefix``; with ``-X importtime`` so that what it imported is on stderr."""
    environment = dict(os.environ, PYTHONPYCACHEPREFIX=str(prefix), COLUMNS=str(columns))
    environment.pop("PYTHONDONTWRITEBYTECODE", None)
    environment.update(env)
    return subprocess.run(
        [sys.executable, "-X", "importtime", "-c", CONSOLE, *argv],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
        env=environment,
    )


def _imported(stderr: str) -> set[str]:
    return {line.rpartition("|")[2].strip() for line in stderr.splitlines() if "|" in line}


def _argparse_help(columns: int, monkeypatch: pytest.MonkeyPatch) -> str:
    monkeypatch.setenv("COLUMNS", str(columns))
    return build_parser().format_help()


def _kept(prefix: Path) -> list[Path]:
    return sorted(prefix.rglob("help.*.txt"))


@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_is_argparses_and_is_kept(flag, tmp_path, monkeypatch) -> None:
    first = _console(flag, prefix=tmp_path, columns=100)
    assert first.stdout == _argparse_help(100, monkeypatch)
    assert "argparse" in _imported(first.stderr)  # formatted this once
    assert len(_kept(tmp_path)) == 1
    again = _console(flag, prefix=tmp_path, columns=100)
    assert again.stdout == first.stdout
    assert "argparse" not in _imported(again.stderr)  # read back
    assert len(_kept(tmp_path)) == 1


def test_another_width_is_formatted_afresh_and_kept_beside(tmp_path, monkeypatch) -> None:
    _console("--help", prefix=tmp_path, columns=100)
    narrow = _console("--help", prefix=tmp_path, columns=50)
    assert narrow.stdout == _argparse_help(50, monkeypatch)
    assert "argparse" in _imported(narrow.stderr)
    assert len(_kept(tmp_path)) == 2


def test_another_language_is_formatted_afresh(tmp_path) -> None:
    _console("--help", prefix=tmp_path)
    other = _console("--help", prefix=tmp_path, LANGUAGE="de")
    assert "argparse" in _imported(other.stderr)


def test_a_kept_help_for_another_key_is_not_shown(tmp_path) -> None:
    """A kept file whose first line is not this run's key (another build wrote it, or it was
    edited) is formatted afresh and replaced, never shown."""
    shown = _console("--help", prefix=tmp_path).stdout
    (kept,) = _kept(tmp_path)
    kept.write_text("not this key\nusage: something else\n", encoding="utf-8")
    again = _console("--help", prefix=tmp_path)
    assert again.stdout == shown
    assert "argparse" in _imported(again.stderr)
    assert kept.read_text(encoding="utf-8").endswith(shown)


def test_nothing_is_kept_when_python_writes_no_bytecode(tmp_path, monkeypatch) -> None:
    shown = _console("--help", prefix=tmp_path, PYTHONDONTWRITEBYTECODE="1")
    assert shown.stdout == _argparse_help(80, monkeypatch)
    assert _kept(tmp_path) == []


def test_version_is_argparses_without_a_parser(tmp_path, capsys) -> None:
    shown = _console("--version", prefix=tmp_path)
    assert "argparse" not in _imported(shown.stderr)
    with pytest.raises(SystemExit) as exited:
        main(["--version"])
    assert exited.value.code == 0
    assert shown.stdout == capsys.readouterr().out


def test_a_reader_that_leaves_early_is_no_error(tmp_path) -> None:
    """``reform-sim --help | head -1``, from the kept help: the pipe is gone before the write."""
    environment = dict(os.environ, PYTHONPYCACHEPREFIX=str(tmp_path))
    environment.pop("PYTHONDONTWRITEBYTECODE", None)
    for _ in range(2):  # formatted, then kept
        process = subprocess.Popen(
            [sys.executable, "-c", CONSOLE, "--help"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            cwd=ROOT,
            env=environment,
        )
        process.stdout.close()
        err = process.stderr.read().decode()
        assert process.wait(timeout=60) == 0, err
        assert err == ""

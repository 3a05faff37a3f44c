"""Running ``reform-sim`` in a test and taking its one-line error."""

from __future__ import annotations

from typing import Any

from sim.cli import main


def cli_error(argv: list[Any], capsys: Any) -> str:
    """Runs ``reform-sim argv`` (each item made a string), asserts exit status 2 and a single
    line on stderr, and returns that line."""
    status = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1, err
    return err.strip()

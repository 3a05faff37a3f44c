"""Numbers as a command line takes them: written in ASCII, as people type counts and sizes."""

from __future__ import annotations

__all__ = ["ascii_float", "ascii_int"]


def ascii_int(text: str) -> int:
    """``int(text)`` of a number written in ASCII digits: Python's int() also reads other
    scripts' digits ('٣' is 3), which no one types for a count on purpose."""
    if not str(text).isascii():
        raise ValueError(f"expected ASCII digits, got {text!r}")
    return int(text)


def ascii_float(text: str) -> float:
    """``float(text)`` of a number written in ASCII characters (see `ascii_int`)."""
    if not str(text).isascii():
        raise ValueError(f"expected ASCII digits, got {text!r}")
    return float(text)


ascii_int.__name__, ascii_float.__name__ = "int", "float"  # argparse: "invalid int value: '٣'"

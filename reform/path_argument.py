"""The one check of a path handed to a public function: a clear error naming the function and
the argument, instead of a TypeError from deep inside ``pathlib`` or ``os``."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

__all__ = ["path_argument"]


def path_argument(value: Any, *, name: str, function: str) -> Path:
    """``value`` as a `Path`, if it is a non-empty ``str`` or ``os.PathLike`` of one.

    Args:
        value: what the caller passed.
        name: the argument's name (``"path"``), for the message.
        function: the public function's name (``"load_dataset"``), for the message.

    Raises:
        TypeError: ``value`` is None, bytes, a number, a list... (the message names the type).
        ValueError: an empty string (it would mean the current folder without saying so) or
            one holding a NUL character.
    """
    if isinstance(value, os.PathLike):
        text = os.fspath(value)
    else:
        text = value
    if not isinstance(text, str):
        raise TypeError(
            f"{function}: {name} must be a path (a str or os.PathLike), got "
            f"{type(value).__name__}{'' if value is None else f' {_short(value)}'}"
        )
    if not text:
        raise ValueError(f"{function}: {name} must be a path, got an empty string")
    if "\0" in text:
        raise ValueError(f"{function}: {name} must be a path, got {_short(text)} (a NUL character)")
    return Path(text)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else f"{text[:60]}… ({len(text):,} characters)"

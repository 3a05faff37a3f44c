"""The one error every loader raises for a malformed file."""

from __future__ import annotations

import errno
import functools
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    import numpy as np

F = TypeVar("F", bound=Callable[..., Any])

# Longest offending value a message quotes whole, characters; longer ones are cut, saying so.
FOUND_LIMIT = 120


def shorten(text: str, limit: int = FOUND_LIMIT) -> str:
    """``text`` on one line, cut to about ``limit`` characters, its full length said."""
    text = str(text).replace("\n", "\\n").replace("\r", "\\r")
    if len(text) <= limit:
        return text
    return f"{text[: limit - 20]}… ({len(text):,} characters)"


# What an OSError found, in words, by its errno (the kinds a file system raises on a path).
_OS_ERRORS = {
    errno.EACCES: "no permission to read it",
    errno.EPERM: "no permission to read it",
    errno.ENOENT: "no such file or folder",
    errno.EISDIR: "a folder, not a file",
    errno.ENOTDIR: "a path through something that is not a folder",
    errno.ELOOP: "a symbolic link loop",  # as reform.atomic.file_kind says it
    errno.ENAMETOOLONG: "a name too long for the file system",
}


def os_error_found(exc: OSError) -> str:
    """What an `OSError` on a path found, as a message's "found" says it: ``no permission to
    read it``, ``a symbolic link loop``, or the system's own words."""
    return _OS_ERRORS.get(exc.errno) or str(exc.strerror or exc)


def damaged_found(kind: str, detail: str) -> str:
    """A file its reader could not parse, as a message's "found" says it: ``a damaged or
    cut-short Parquet file (the reader's words)``; the reader's words on one line, without
    the exception's name."""
    words = " ".join(str(detail).split())
    return f"a damaged or cut-short {kind} ({words})" if words else f"a damaged {kind}"


def _float_repr(value: Any) -> str:
    return repr(float(value))


class DataFormatError(ValueError):
    """A data file does not hold what its format promises.

    The message names the file, where in it (line, frame, row), the field, what was expected
    and what was found, then what to do about it when there is something to do, e.g.::

        features.txt: line 12, person 3: field 'x': expected a finite number, found 'nan'
    """

    def __init__(
        self,
        path: str | Path,
        where: str | None,
        field: str | None,
        expected: str,
        found: str,
        hint: str | None = None,
    ) -> None:
        self.path = Path(path)
        # A store's URI (s3://bucket/key) stays as given: a Path would fold its "//".
        shown = path if isinstance(path, str) and "://" in path else str(self.path)
        self.where = where
        self.field = field
        self.expected = expected
        self.found = found
        self.hint = hint
        self._shown = shown
        parts = [shown]
        if where:
            parts.append(where)
        detail = f"field {field!r}: " if field else ""
        parts.append(f"{detail}expected {expected}, found {shorten(found)}")
        message = ": ".join(parts)
        super().__init__(f"{message}; {hint}" if hint else message)

    @classmethod
    def check_rows(
        cls,
        bad: np.ndarray,
        path: str | Path,
        where: Callable[[int], str],
        field: str | None,
        expected: str,
        values: np.ndarray | None = None,
        show: Callable[[Any], str] = _float_repr,
    ) -> None:
        """Raises one naming the first row where ``bad`` holds; returns when none does.

        Args:
            bad: (n,) bool, the rows (or elements) that break the rule.
            path: the file.
            where: the message's place for that row's 0-based index (``f"row {row + 1}"``).
            field: the field, or None.
            expected: what the rule asks.
            values: (n,) the values checked: the message shows that row's, written by ``show``
                (by default ``repr(float(value))``); None when a breach has no value to show
                (a null), and ``show(None)`` says what was found.
        """
        rows = bad.nonzero()[0]
        if rows.size:
            row = int(rows[0])
            raise cls(
                path, where(row), field, expected, show(None if values is None else values[row])
            )

    def __reduce__(self) -> tuple:
        # Rebuilt from its fields, so that it survives pickling (errors of worker processes).
        fields = (self._shown, self.where, self.field, self.expected, self.found, self.hint)
        return type(self), fields


def file_errors_as_data_errors(function: F) -> F:
    """``function`` with any `OSError` it lets through (a file or folder it cannot stat or
    open: no permission, a link loop) raised as one `DataFormatError` naming that file, so that
    a loader's caller meets one error type whatever the file system does."""

    @functools.wraps(function)
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        try:
            return function(*args, **kwargs)
        except OSError as exc:
            where = exc.filename if exc.filename is not None else (args[0] if args else "?")
            raise DataFormatError(
                where,
                None,
                None,
                "a readable dataset file or folder",
                os_error_found(exc),
            ) from None

    return wrapped  # type: ignore[return-value]

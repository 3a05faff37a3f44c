"""The one error every loader raises for a malformed file."""

from __future__ import annotations

from pathlib import Path


class DataFormatError(ValueError):
    """A data file does not hold what its format promises.

    The message names the file, where in it (line, frame, row), the field, what was expected
    and what was found, e.g.::

        features.txt: line 12: field 'x' of person 3: expected a finite number, found 'nan'
    """

    def __init__(
        self,
        path: str | Path,
        where: str | None,
        field: str | None,
        expected: str,
        found: str,
    ) -> None:
        self.path = Path(path)
        self.where = where
        self.field = field
        self.expected = expected
        self.found = found
        parts = [str(self.path)]
        if where:
            parts.append(where)
        detail = f"field {field!r}: " if field else ""
        parts.append(f"{detail}expected {expected}, found {found}")
        super().__init__(": ".join(parts))

"""pyarrow, which Rerun converts every logged value with, kept from importing pandas.

pyarrow looks for pandas the first time it converts a numpy array (is it a pandas Series?) and
whenever it infers the type of a Python sequence (are these pandas' missing-value markers?), and
imports pandas to find out: a fifth of a second of CPU time, more than any of the project's own
modules costs, in a command that hands pyarrow no pandas object. :func:`pandas_withheld` has
``import pandas`` fail while a command writes its recordings, and pyarrow carries on without it.

pyarrow keeps its first answer: for the rest of the process, until something asks for pandas
outright (``Table.to_pandas``, ``Table.from_pandas``, which import it as always), ``pa.array``
and ``pa.table`` given a pandas object take it for a plain sequence or mapping. Hence only a
command that ends with its recordings withholds pandas; the library's functions never do.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator

__all__ = ["pandas_withheld"]


class _Withheld:
    """A finder that has ``import pandas`` fail."""

    @staticmethod
    def find_spec(name: str, path: object = None, target: object = None) -> None:  # noqa: ARG004
        if name.partition(".")[0] == "pandas":
            raise ModuleNotFoundError("pandas is withheld while recordings are written", name=name)


@contextlib.contextmanager
def pandas_withheld() -> Iterator[None]:
    """Within it, ``import pandas`` fails, unless pandas was imported before (then nothing
    changes: pyarrow finds it at no cost)."""
    if "pandas" in sys.modules:
        yield
        return
    finder = _Withheld()
    sys.meta_path.insert(0, finder)
    try:
        yield
    finally:
        sys.meta_path.remove(finder)

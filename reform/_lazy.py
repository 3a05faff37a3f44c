"""Package attributes loaded on first use (PEP 562), so that importing a package stays light."""

from __future__ import annotations

import sys

TYPE_CHECKING = False  # typing's own flag without importing typing (type checkers know it)
if TYPE_CHECKING:  # importing no more than Python has at start: every command imports this
    from collections.abc import Callable, Mapping
    from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(
    package: str, exports: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A package's module-level ``__getattr__`` and ``__dir__`` for names defined elsewhere.

    Args:
        package: the package's ``__name__``.
        exports: public name -> the module defining it; the module is imported the first time
            the name is looked up, and the value is then cached on the package. Any other name
            that is a module of the package (``package.name``) is imported when looked up.

    Returns:
        ``(__getattr__, __dir__)``, to assign at the package's top level.
    """

    def __getattr__(name: str) -> Any:
        import importlib
        import importlib.util

        module = exports.get(name)
        if module is None:
            # A subpackage or module of the package (``reform.datasets``), as an eager
            # ``__init__`` importing its modules would have made it an attribute.
            if importlib.util.find_spec(f"{package}.{name}") is None:
                raise AttributeError(f"module {package!r} has no attribute {name!r}")
            return importlib.import_module(f"{package}.{name}")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__

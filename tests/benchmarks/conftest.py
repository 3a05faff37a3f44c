"""What the benchmark scripts' tests share: a script loaded as a module."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCHMARKS_DIR = Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.fixture(scope="session")
def documented_commands():
    """``benchmarks/documented_commands.py`` as a module (it imports ``timing`` from beside it,
    as when run)."""
    sys.path.insert(0, str(BENCHMARKS_DIR))
    try:
        path = BENCHMARKS_DIR / "documented_commands.py"
        spec = importlib.util.spec_from_file_location("documented_commands", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = module  # its dataclasses look their module up there
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.path.remove(str(BENCHMARKS_DIR))
        sys.modules.pop("documented_commands", None)

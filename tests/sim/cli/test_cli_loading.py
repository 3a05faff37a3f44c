"""A command whose module imports for seconds says so first, on a terminal only
(`sim.cli._grammar.run_loading`): a line with the time so far, redrawn while the import works and
cleared when the command begins; a log or a pipe gets nothing more."""

from __future__ import annotations

import importlib
import io
import sys
from argparse import Namespace

import pytest

from sim.cli._grammar import run_loading

# A command's module whose imports take 2.5 s (MuJoCo and scikit-learn: 2 to 7 s on two cores).
SLOW_MODULE = "import time\n\ntime.sleep(2.5)\n\n\ndef run(args):\n    return 7\n"


class _Terminal(io.StringIO):
    """A stderr that is a terminal."""

    def isatty(self) -> bool:
        return True


@pytest.fixture
def slow_module(tmp_path, monkeypatch):
    """The name of a module, not yet imported, whose import sleeps 2.5 s."""
    name = f"slow_command_{tmp_path.name.replace('-', '_')}"
    (tmp_path / f"{name}.py").write_text(SLOW_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield name
    sys.modules.pop(name, None)


def test_a_terminal_sees_what_loads_while_it_loads(slow_module, monkeypatch):
    monkeypatch.setattr(sys, "stderr", _Terminal())
    handler = run_loading(f"{slow_module}:run", "MuJoCo")
    assert handler(Namespace(quiet=False)) == 7
    err = sys.stderr.getvalue()
    assert "loading MuJoCo: 00:00 so far" in err, err  # at once, before the import's end
    assert "loading MuJoCo: 00:02 so far" in err, err  # redrawn while it works
    assert err.endswith("\r"), err  # cleared: the command's first line stands alone
    assert handler.target == f"{slow_module}:run"


@pytest.mark.parametrize(
    ("stderr", "quiet"), [(io.StringIO, False), (_Terminal, True)], ids=["a-log", "quiet"]
)
def test_a_log_or_quiet_gets_nothing_more(slow_module, monkeypatch, stderr, quiet):
    monkeypatch.setattr(sys, "stderr", stderr())
    assert run_loading(f"{slow_module}:run", "MuJoCo")(Namespace(quiet=quiet)) == 7
    assert sys.stderr.getvalue() == ""


def test_a_module_already_loaded_says_nothing(slow_module, monkeypatch):
    importlib.import_module(slow_module)
    monkeypatch.setattr(sys, "stderr", _Terminal())
    assert run_loading(f"{slow_module}:run", "MuJoCo")(Namespace(quiet=False)) == 7
    assert sys.stderr.getvalue() == ""

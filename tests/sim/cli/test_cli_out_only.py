"""The experiments that generate data of their own (sim2real's synthetic crowds, the twins' data)
write it under --out unless told otherwise: nothing lands in the folder the command runs from.

The experiments themselves take minutes; these tests stop each at its first call into the
library, whose paths are the command's whole wiring."""

from __future__ import annotations

from pathlib import Path

import pytest

from sim.cli import main


class _Reached(Exception):
    """Raised by the stand-in of an experiment's library call, holding its arguments."""


def _stand_in(*args, **kwargs):
    raise _Reached(args, kwargs)


@pytest.fixture
def elsewhere(tmp_path, monkeypatch) -> Path:
    """The folder the command runs from, empty, and checked empty afterwards."""
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    yield cwd
    assert not list(cwd.iterdir()), f"written outside --out: {list(cwd.iterdir())}"


@pytest.mark.parametrize(
    ("experiment", "loader", "call", "root", "option", "default"),
    [
        ("sim2real", "load_named", "sim_to_real", "synthetic_root", "--synthetic", "synthetic"),
        ("twins", "_load", None, "root", "--twins", "twins"),
    ],
)
@pytest.mark.parametrize("given", [False, True])
def test_an_experiment_s_own_data_go_under_out(
    experiment, loader, call, root, option, default, given, tmp_path, elsewhere, monkeypatch
):
    import importlib

    module = importlib.import_module(f"sim.cli.experiment_{experiment}")
    monkeypatch.setattr(module, loader, lambda _data: {"salsa": None, "babble": None})
    if call is not None:
        monkeypatch.setattr(module, call, _stand_in)
    else:  # imported by the command when it runs
        monkeypatch.setattr("sim.experiments.twins.run_twins", _stand_in)
    out = tmp_path / "out"
    argv = ["experiment", experiment, "--out", str(out), "--quiet"]
    if given:
        argv += [option, str(tmp_path / "mine")]
    with pytest.raises(_Reached) as reached:
        main(argv)
    _, kwargs = reached.value.args
    assert Path(kwargs[root]) == (tmp_path / "mine" if given else out / default)
    if experiment == "sim2real":
        assert Path(kwargs["out_model"]) == out / "recommended.skops"

"""The extending guide's promises, followed literally: its detector code, copied from the page,
registers a detector whose declared option appears in --help and is set by --option."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from toy_scenes import toy_frames

import reform.detectors
from reform import Dataset, write_parquet
from sim.cli import main

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "extending.md"


def _python_blocks() -> list[str]:
    return re.findall(r"```python[^\n]*\n(.*?)```", GUIDE.read_text(), flags=re.S)


@pytest.fixture
def registry(monkeypatch):
    monkeypatch.setattr(reform.detectors, "_REGISTRY", dict(reform.detectors._REGISTRY))


def test_the_guides_detector_with_declared_options_runs_from_the_command_line(
    registry, tmp_path, capsys
):
    blocks = _python_blocks()
    (close,) = [b for b in blocks if "connected_components" in b and "class Close" in b]
    (declared,) = [b for b in blocks if "Option(" in b and "register_detector(" in b]
    namespace: dict = {}
    exec(compile(close + "\n" + declared, str(GUIDE), "exec"), namespace)  # the page's code

    with pytest.raises(SystemExit):
        main(["evaluate", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "close: people within a radius, chained" in help_text
    assert "radius: a float in m from 0.1 to 5, default 1.0; how close is together" in help_text

    data = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 10)), name="toy", source="toy"), data)
    out = tmp_path / "groups.json"
    argv = ["detect", "--detector", "close", "--option", "radius=0.8", "--data", str(data)]
    assert main([*argv, "--out", str(out)]) == 0, capsys.readouterr().err
    assert json.loads(out.read_text())["detector"] == "close"
    assert reform.detectors.make_detector("close", radius=0.8).radius == 0.8
    assert reform.detectors.make_detector("close").radius == 1.0  # the declared default
    bad = ["detect", "--detector", "close", "--option", "radius=9", "--data", str(data)]
    assert main([*bad, "--out", str(tmp_path / "x.json")]) == 2
    assert "option radius expects a float in m from 0.1 to 5" in capsys.readouterr().err

"""Every command whose work splits into units gives the same results, bit for bit, on local
processes and on a real local Ray instance: the JSON it writes is compared, and the rest of what
it writes where it holds no timings."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sim.cli import main

# What a run records about itself rather than about its results: how long it took, on what,
# and the command line (which names the backend).
RUN_RECORD = {"command", "timings_s", "environment", "jobs", "seconds", "timings"}


def _results(path: Path) -> dict:
    """The JSON file's content without the run's record of itself, at any depth."""

    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if k not in RUN_RECORD}
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    return strip(json.loads(path.read_text()))


def _run(argv: list[str], out: Path, backend: list[str]) -> None:
    assert main([*argv, "--out", str(out), *backend]) == 0


LOCAL = ["--jobs", "2"]
RAY = ["--backend", "ray"]


@pytest.mark.slow
def test_stress(ray_instance, tmp_path) -> None:
    argv = ["stress", "--grid", "small", "--axes", "dropout,sensor", "--episodes", "1"]
    _run(argv, tmp_path / "local", LOCAL)
    _run(argv, tmp_path / "ray", RAY)
    local, ray = (
        _results(tmp_path / "local" / "stress.json"),
        _results(tmp_path / "ray" / "stress.json"),
    )
    assert [a["name"] for a in local["axes"]] == ["dropout", "sensor"]
    assert local["axes"][0]["points"][0]["frames"] > 0
    assert ray == local
    ran = json.loads((tmp_path / "ray" / "stress.json").read_text())
    assert ran["environment"]["backend"] == "ray" and ran["jobs"] == 2
    assert "--backend ray" in ran["command"]


@pytest.mark.slow
def test_benchmark(ray_instance, tmp_path, shared_datasets) -> None:
    argv = ["benchmark", "--data", str(shared_datasets / "babble")]
    argv += ["--data", str(shared_datasets / "coffeebreak")]
    argv += ["--detector", "gcff", "--detector", "gcff-own", "--detector", "majority"]
    argv += ["--quiet"]
    _run(argv, tmp_path / "local", LOCAL)
    _run(argv, tmp_path / "ray", RAY)
    local = _results(tmp_path / "local" / "benchmark.json")
    assert local["cells"][0]["scores"]["frames"] > 0
    assert local == _results(tmp_path / "ray" / "benchmark.json")


@pytest.mark.slow
def test_calibrate(ray_instance, tmp_path, shared_datasets) -> None:
    argv = ["calibrate", "--data", str(shared_datasets), "--episodes", "1", "--quiet"]
    _run(argv, tmp_path / "local", LOCAL)
    _run(argv, tmp_path / "ray", RAY)
    local = _results(tmp_path / "local" / "calibration.json")
    assert local and local == _results(tmp_path / "ray" / "calibration.json")

"""What a frame costs a detector (``frame_bytes``): each built-in's figure holds what it takes
when it predicts, and frames larger than a run may hold are refused before any is predicted,
naming how many people fit."""

from __future__ import annotations

import numpy as np
import pytest
from cli_errors import cli_error
from toy_scenes import toy_frames
from traced import traced_peak

import reform.detectors
from reform import Dataset, Frame, Reform
from reform.datasets import write_parquet
from reform.detectors import (
    FrameTooLarge,
    check_frame_memory,
    frame_memory,
    make_detector,
    register_detector,
)
from reform.smoothing import SlidingMajority

MIB = 2**20


def crowd(n: int, *, seed: int, per_person_m2: float, time: float = 0.0) -> Frame:
    """``n`` people at random on a square floor of ``per_person_m2`` each, facing anywhere."""
    rng = np.random.default_rng(seed)
    side = float(np.sqrt(n * per_person_m2))
    return Frame(
        ids=np.arange(n),
        position=rng.uniform(0.0, side, (n, 2)),
        yaw=rng.uniform(-np.pi, np.pi, n),
        time=time,
    )


@pytest.fixture(scope="module")
def toy_reform() -> Reform:
    return Reform().fit(toy_frames(0, 30))


def _detectors(toy_reform: Reform) -> dict[str, object]:
    return {
        "gcff": make_detector("gcff"),
        "dominant-sets": make_detector("dominant-sets"),
        "gtcg": make_detector("gtcg"),
        "reform": toy_reform,
        "smoothed gcff": SlidingMajority(make_detector("gcff"), window=2.0),
    }


@pytest.mark.parametrize("per_person_m2", [9.0, 2.0], ids=["concourse", "party"])
def test_each_built_in_takes_no_more_than_it_says(toy_reform, per_person_m2):
    # Two frames of each size in one call, as a dataset is predicted; sizes where the
    # quadratic terms dominate what every frame costs anyway.
    for name, detector in _detectors(toy_reform).items():
        detector.predict([crowd(20, seed=9, per_person_m2=per_person_m2)])  # imports, caches
        for n in (100, 200):
            frames = [crowd(n, seed=s, per_person_m2=per_person_m2, time=0.5 * s) for s in (1, 2)]
            _, peak = traced_peak(lambda d=detector, f=frames: d.predict(f))
            said = frame_memory(detector, n)
            assert said is not None and peak <= said, (name, n, peak, said)
            # and not a figure so loose that it would refuse frames it runs within a tenth
            assert said <= 10 * peak + 40 * MIB, (name, n, peak, said)


def test_frame_memory_reads_what_a_detector_says_and_nothing_else():
    class Says:
        def __init__(self, figure):
            self.figure = figure

        def frame_bytes(self, n_people):
            if isinstance(self.figure, Exception):
                raise self.figure
            return self.figure

    assert frame_memory(Says(1234.2), 10) == 1235
    assert frame_memory(object(), 10) is None
    for nonsense in (RuntimeError("no idea"), -1, float("nan"), float("inf"), "1 GiB", True):
        assert frame_memory(Says(nonsense), 10) is None, nonsense


def test_a_frame_too_large_is_refused_with_the_people_that_fit():
    detector = make_detector("dominant-sets")
    frames = [crowd(n, seed=n, per_person_m2=4.0, time=float(k)) for k, n in enumerate((5, 150, 7))]
    limit = frame_memory(detector, 100)
    with pytest.raises(FrameTooLarge) as refused:
        check_frame_memory(
            "dominant-sets",
            detector,
            frames,
            limit=limit,
            limit_text="the limit given",
            source="lab.parquet",
            hint="ask for less",
        )
    assert frame_memory(detector, 100) <= limit < frame_memory(detector, 101)  # 100 fit
    assert frame_memory(detector, 150) == 150 * 150 * 80  # 1.72 MiB
    assert str(refused.value) == (
        "dominant-sets: frame 1 (t=1 s) of lab.parquet holds 150 people, which would take about "
        "1.72 MiB to predict, more than the limit given: at most 100 people a frame fit; ask for "
        "less"
    )
    # the largest frame fits: nothing to say
    check_frame_memory("d", detector, frames, limit=frame_memory(detector, 150), limit_text="x")


def test_a_detector_that_caps_its_frames_is_held_to_its_cap():
    detector = make_detector("gcff")
    frames = [crowd(50, seed=1, per_person_m2=4.0)]
    with pytest.raises(
        FrameTooLarge,
        match=r"more than the 39.1 KiB gcff allows one frame, whatever the memory given: at most "
        r"\d+ people a frame fit$",
    ):
        detector.max_frame_bytes = 40_000  # an instance's own, below the limit given
        check_frame_memory(
            "gcff", detector, frames, limit=2**40, limit_text="--max-memory 1 TiB", hint="h"
        )


@pytest.fixture
def oversized(monkeypatch, tmp_path):
    """A registered detector that says a frame of 50 people costs more than anything has, and
    fails if it is ever asked to predict; and a dataset with such a frame."""
    monkeypatch.setattr(reform.detectors, "_REGISTRY", dict(reform.detectors._REGISTRY))

    class Oversized:
        def frame_bytes(self, n_people):
            return 2**50 if n_people >= 50 else 0

        def predict(self, frames):
            raise RuntimeError("predicted")

    register_detector("oversized", Oversized, help="says a crowd costs a petabyte")
    frames = tuple(
        crowd(n, seed=k, per_person_m2=4.0, time=float(k)).replace(groups=((0, 1),))
        for k, n in enumerate((10, 60))
    )
    path = tmp_path / "lab.parquet"
    write_parquet(Dataset(frames=frames, name="lab"), path)
    return path


@pytest.mark.parametrize("command", ["evaluate", "detect"])
def test_evaluate_and_detect_refuse_a_frame_too_large_before_predicting(oversized, command, capsys):
    out = ["--out", oversized.parent / "detections.json"] if command == "detect" else []
    line = cli_error(
        [command, "--detector", "oversized", "--data", oversized, "--max-memory", "64G", *out],
        capsys,
    )
    assert line == (
        f"reform-sim {command}: error: oversized: frame 1 (t=1 s) of {oversized} holds 60 "
        "people, which would take about 1 PiB to predict, more than --max-memory "
        "64 GiB: at most 49 people a frame fit; give a larger --max-memory, or fewer people a "
        "frame"
    )


def test_benchmark_refuses_a_frame_too_large_before_any_cell(oversized, tmp_path, capsys):
    out = tmp_path / "report"
    line = cli_error(
        [
            "benchmark",
            "--data",
            oversized,
            "--detector",
            "majority",
            "--detector",
            "oversized",
            "--max-memory",
            "64G",
            "--jobs",
            "1",
            "--out",
            out,
            "-q",
        ],
        capsys,
    )
    assert line.startswith(
        "reform-sim benchmark: error: oversized: frame 1 (t=1 s) of lab.parquet "
    )
    assert "more than --max-memory 64 GiB: at most 49 people a frame fit; give a larger" in line
    assert not out.exists()


def test_a_malformed_max_memory_is_refused_before_the_data_is_read(tmp_path, capsys):
    missing = tmp_path / "nowhere.parquet"
    for command in ("evaluate", "detect"):
        out = ["--out", tmp_path / "detections.json"] if command == "detect" else []
        line = cli_error(
            [command, "--detector", "gcff", "--data", missing, "--max-memory", "lots", *out],
            capsys,
        )
        assert line.startswith(f"reform-sim {command}: error: --max-memory: expected a size"), line

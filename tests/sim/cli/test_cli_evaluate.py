"""``reform-sim evaluate`` and ``reform-sim detect``, end to end on the real datasets."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest
from cli_errors import cli_json, run_cli

from reform.datasets import load_dataset
from sim.cli import main
from sim.cli._common import CliError
from sim.cli._detectors import (
    DETECTORS,
    DetectorSpec,
    add_detector_arguments,
    build_detector,
    detector_params,
)
from sim.experiments.tables import format_comparison, format_report


@pytest.fixture
def as_majority(monkeypatch):
    """Installs a detector object under the name ``majority`` for one test."""

    def install(detector) -> None:
        spec = DetectorSpec("majority", "test", lambda args: detector)
        monkeypatch.setitem(DETECTORS, "majority", spec)

    return install


def test_evaluate_majority_on_salsa(salsa_dir, tmp_path, capsys):
    out_json, out_md = tmp_path / "r" / "salsa.json", tmp_path / "salsa.md"
    result, out, err = cli_json(
        [
            "evaluate",
            "--detector",
            "majority",
            "--data",
            salsa_dir,
            "--json",
            out_json,
            "--markdown",
            out_md,
        ],
        out_json,
        capsys,
    )
    assert result["schema_version"] == 1
    assert (result["detector"], result["dataset"], result["frames"]) == ("majority", "salsa", 1143)
    assert result["sequences"] == {"session1": 644, "session2": 499}
    # Every annotated SALSA frame holds 18 people: 153 pairs each.
    assert result["pairs"]["total"] == 1143 * 153
    assert result["pairs"]["predicted_together"] == 0
    assert 0.80 < result["pairwise_accuracy"] < 0.88  # paper: 85.3 on its test split
    for t in ("2/3", "1"):
        # Nothing detected: P = 1 in every frame, R = 0 wherever there is a true group (all).
        assert (result[t]["precision"], result[t]["recall"], result[t]["f1"]) == (1.0, 0.0, 0.0)
        assert result[t]["micro"]["tp"] == 0 and result[t]["micro"]["fn"] == 5395
        # SALSA's group-size histogram (datasets/salsa/README.md, "both, canonical").
        sizes = {b["size"]: b["true_groups"] for b in result[t]["by_size"]}
        assert sizes == {2: 1554, 3: 1705, 4: 952, 5: 539, 6: 381, 7: 238, 8: 25, 12: 1}
    assert set(result["by_sequence"]) == {"session1", "session2"}
    # The printed table is the report of the saved JSON; the Markdown file its Markdown form.
    assert out == format_report(result, style="text")
    assert out_md.read_text() == format_report(result, style="markdown")
    assert "Pairwise accuracy: 83.3 %" in out
    assert not [p for p in tmp_path.rglob("*.tmp")]
    # SALSA's ground truth leaves people in no group: read as alone, counted, and said
    assert (
        f"note: {salsa_dir}: read with repairs (--strict refuses them): "
        "people_missing_from_groundtruth 129, duplicate_singletons 3; the first: "
    ) in err


def test_evaluate_majority_on_babble(babble_dir, tmp_path, capsys):
    out_json = tmp_path / "babble.json"
    result, out, err = cli_json(
        [
            "evaluate",
            "--detector",
            "majority",
            "--data",
            babble_dir,
            "--json",
            out_json,
            "--per-frame",
        ],
        out_json,
        capsys,
    )
    assert result["dataset"] == "babble" and result["frames"] == len(result["per_frame"])
    frames = load_dataset(babble_dir).annotated()
    assert result["frames"] == len(frames)
    # Frames with no true F-formation score R = 1, all others R = 0, so R̄ is their share.
    empty = sum(1 for f in frames if not f.fformations())
    assert result["2/3"]["recall"] == pytest.approx(empty / len(frames))
    assert [r["time"] for r in result["per_frame"]] == [f.time for f in frames]
    assert "majority on babble" in out


def test_detect_majority_writes_every_frame(salsa_dir, tmp_path, capsys):
    out = tmp_path / "groups.json"
    result, _, err = cli_json(
        ["detect", "--detector", "majority", "--data", salsa_dir, "--out", out], out, capsys
    )
    assert result["kind"] == "reform-sim/detections" and result["schema_version"] == 1
    assert len(result["frames"]) == 1145  # every frame, the two without ground truth included
    first = result["frames"][0]
    assert first == {"index": 0, "sequence": "session1", "time": 0.2, "groups": []}
    assert "1,145 frames, 0 F-formations" in err

    status, _, err = run_cli(
        ["detect", "--detector", "majority", "--data", salsa_dir, "--out", out, "--frames", "all"],
        capsys,
    )
    assert status == 0, err
    assert len(json.loads(out.read_text())["frames"]) == 1143


def test_detect_writes_groups_sorted_without_singletons(salsa_dir, tmp_path, capsys, as_majority):
    truth = {(f.sequence, f.time): f.partition() for f in load_dataset(salsa_dir).annotated()}

    class Oracle:
        """Predicts the ground truth (known beforehand: detectors are not given it), shuffled:
        groups in reverse, members descending."""

        def predict(self, frames):
            return [
                tuple(tuple(sorted(g, reverse=True)) for g in truth[f.sequence, f.time][::-1])
                for f in frames
            ]

    as_majority(Oracle())
    out = tmp_path / "groups.json"
    status, _, err = run_cli(
        ["detect", "--detector", "majority", "--data", salsa_dir, "--out", out, "--frames", "all"],
        capsys,
    )
    assert status == 0, err
    frames = load_dataset(salsa_dir).annotated()
    written = json.loads(out.read_text())["frames"]
    expected = sorted(sorted(g) for g in frames[0].fformations())
    assert written[0]["groups"] == expected
    assert all(len(g) >= 2 for record in written for g in record["groups"])


def test_detect_rejects_a_detector_that_returns_no_partition(
    salsa_dir, tmp_path, capsys, as_majority
):
    class Broken:
        def predict(self, frames):
            return [((1, 2),) for _ in frames]  # forgets everyone else

    as_majority(Broken())
    out = tmp_path / "groups.json"
    status, _, err = run_cli(
        ["detect", "--detector", "majority", "--data", salsa_dir, "--out", out], capsys
    )
    assert status == 2
    assert "detector output for frame 0 (session1 t=0.2 s): person 3 is in no group" in err
    assert not out.exists()


def test_bad_data_path_is_one_clear_line(tmp_path, capsys):
    status, out, err = run_cli(
        ["evaluate", "--detector", "majority", "--data", tmp_path / "missing"], capsys
    )
    assert status == 2 and out == ""
    assert err.startswith("reform-sim evaluate: error: ") and "missing" in err
    assert len(err.strip().splitlines()) == 1


def test_unknown_detector_is_an_argparse_error(salsa_dir, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", "--detector", "oracle", "--data", str(salsa_dir)])
    assert exc.value.code == 2
    assert "invalid choice: 'oracle'" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["evaluate", "detect"])
def test_help_lists_the_detectors(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    assert "majority" in capsys.readouterr().out


def test_detector_registry():
    parser = argparse.ArgumentParser()
    add_detector_arguments(parser)
    args = parser.parse_args(["--detector", "majority"])
    detector = build_detector(args)
    assert type(detector).__name__ == "Majority"
    assert detector_params(detector) == {}


def test_detector_params_of_a_get_params_of_its_own():
    class NoDeep:
        def get_params(self):
            return {"radius": np.float64(1.5)}

    class Raises:
        def get_params(self, deep=True):
            raise RuntimeError("not\nready")

    assert detector_params(NoDeep()) == {"radius": 1.5}
    with pytest.raises(
        CliError, match=r"^the detector's get_params\(\) raised RuntimeError: not ready"
    ):
        detector_params(Raises())


def test_comparison_table_from_results(salsa_dir, tmp_path, capsys):
    out_json = tmp_path / "salsa.json"
    run_cli(["evaluate", "--detector", "majority", "--data", salsa_dir, "--json", out_json], capsys)
    result = json.loads(out_json.read_text())
    table = format_comparison([result], style="markdown").splitlines()
    assert [c.strip() for c in table[0].split("|")[1:-1]] == [
        "detector", "dataset", "frames", "pair acc.", "P@2/3", "R@2/3", "F1@2/3", "P@1", "R@1",
        "F1@1",
    ]  # fmt: skip
    assert [c.strip() for c in table[2].split("|")[1:-1]] == [
        "majority",
        "salsa",
        "1,143",
        "83.3",
        "100.0",
        "0.0",
        "0.0",
        "100.0",
        "0.0",
        "0.0",
    ]

"""The one-command demo end to end (quick budget): report, numbers, recordings, model."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

import scenarios
from reform import evaluate
from reform.datasets import read_parquet
from reform.metrics import T_TWO_THIRDS
from reform.persistence import load_model
from sim.cli import main
from sim.experiments.demo import CLASSIFIER_TEXT, FULL, QUICK, SAVED_CLASSIFIER, run_demo
from sim.experiments.demo_report import write_report
from sim.experiments.sim2real import RECOMMENDED, recipe

SAVED = f"REFORM {CLASSIFIER_TEXT[SAVED_CLASSIFIER]}"


QUIET: dict[str, str] = {}  # what the demo fixture's --quiet run wrote on stderr


@pytest.fixture(scope="module")
def demo(tmp_path_factory, shared_datasets) -> Path:
    """One quick demo run through the command line, with the real datasets."""
    out = tmp_path_factory.mktemp("demo") / "demo-output"
    argv = ["demo", "--quick", "--data", str(shared_datasets), "--out", str(out)]
    with contextlib.redirect_stderr(io.StringIO()) as err:
        assert main([*argv, "--seed", "3", "--jobs", "1", "--quiet"]) == 0
    QUIET["stderr"] = err.getvalue()
    return out


def test_quiet_says_nothing_on_stderr(demo) -> None:
    assert QUIET["stderr"] == ""


def _entities(path: Path) -> set[str]:
    from rerun.chunk import RrdReader

    return {chunk.entity_path for chunk in RrdReader(path).stream()}


def test_says_where_everything_is(demo, capsys) -> None:
    # The fixture ran first in this module; its stdout is gone, so look at the files it names.
    report = (demo / "report.md").read_text()
    assert "reform-sim demo --data" in report and "--quick" in report and "--seed 3" in report
    for section in ("## What ran", "## Scenarios", "## Scores", "## Stress tests", "## Files"):
        assert section in report
    assert "The paper's HRI experiment, re-enacted" in report


def test_report_covers_every_scenario_and_test_set(demo) -> None:
    report = (demo / "report.md").read_text()
    for name in scenarios.names():
        assert f"`{name}`" in report
        assert (demo / "figures" / f"scenario-{name}.png").stat().st_size > 1000
    for test_set in ("held-back synthetic", "SALSA test split", "Babble"):
        assert test_set in report
    assert "![F1 at T = 2/3](figures/scores.png)" in report
    assert (demo / "figures" / "scores.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (demo / "stress" / "stress.md").is_file()
    assert (demo / "hri.md").is_file()


def test_results_json_holds_every_score(demo) -> None:
    data = json.loads((demo / "results.json").read_text())
    assert data["kind"] == "reform-sim/demo"
    assert data["budget"] == "quick" and data["seed"] == 3
    assert data["datasets"] == ["babble", "salsa"]
    assert [s["scenario"] for s in data["scenarios"]] == list(scenarios.names())
    pairs = {(s["detector"], s["dataset"]) for s in data["scores"]}
    for dataset in ("held-back synthetic", "SALSA test split", "Babble"):
        for detector in (
            f"{SAVED} (synthetic)",
            f"{SAVED} (SALSA train)",
            "GCFF (paper: 70 cm, 30000 cm²)",
            "Majority",
        ):
            assert (detector, dataset) in pairs
    for score in data["scores"]:
        assert 0.0 <= score["2/3"]["f1"] <= 1.0
    assert data["recommended"] == RECOMMENDED.to_json()
    assert data["stress"]["kind"] == "reform-sim/stress"
    assert data["hri"]["kind"] == "reform-sim/hri-experiment"
    assert set(data["timings_s"]) >= {"scenarios", "training", "evaluation", "total"}


def test_recordings_hold_people_groups_and_detections(demo) -> None:
    recordings = demo / "recordings"
    for name in scenarios.names():
        entities = _entities(recordings / f"scenario-{name}.rrd")
        assert any(e.startswith("/world") for e in entities), name
        assert any("reform" in e for e in entities), name
        assert any("gcff" in e for e in entities), name
    for test_set in ("held-back-synthetic", "salsa-test-split", "babble"):
        entities = _entities(recordings / f"evaluation-{test_set}.rrd")
        assert any("reform" in e for e in entities) and any("gcff" in e for e in entities)
        assert any(e.startswith("/dataset") for e in entities)
    assert any("stress" in e for e in _entities(recordings / "stress.rrd"))
    for scene in ("hri-conversation", "hri-robot-excluded", "hri-passing"):
        assert (recordings / "hri" / f"{scene}.rrd").is_file()


def test_model_reproduces_the_reported_scores(demo) -> None:
    """The saved model, loaded back, scores the held-back episodes as the report says."""
    model = load_model(demo / "model.skops")
    held = read_parquet(demo / "synthetic" / "held-back").annotated()
    evaluation = evaluate(held, model.predict(held))
    data = json.loads((demo / "results.json").read_text())
    (reported,) = [
        s
        for s in data["scores"]
        if s["detector"] == f"{SAVED} (synthetic)" and s["dataset"] == "held-back synthetic"
    ]
    assert reported["frames"] == evaluation.n_frames
    assert reported["2/3"]["f1"] == pytest.approx(evaluation.at(T_TWO_THIRDS).f1, abs=1e-12)
    # Held-back episodes come from another master seed: none of them was trained on.
    train = {f.sequence for f in read_parquet(demo / "synthetic" / "train").annotated()}
    card = json.loads(next((demo / "synthetic" / "held-back").glob("*/dataset.json")).read_text())
    train_card = json.loads(next((demo / "synthetic" / "train").glob("*/dataset.json")).read_text())
    assert train and card["parameters"]["seed"] != train_card["parameters"]["seed"]


def test_without_real_data_or_recordings(tmp_path, request) -> None:
    """No datasets and --no-recordings: the synthetic parts run, the real rows are left out,
    no recording is written, and every scenario scores as in a run that records."""
    result = run_demo(
        out_dir=tmp_path / "out",
        datasets=None,
        seed=3,
        jobs=1,
        quick=True,
        progress=lambda line: None,
        progress_bars=False,
        recordings=False,
    )
    assert result.datasets == ()
    assert {d for _, d in result.scores} == {"held-back synthetic"}
    assert result.model.is_file()
    assert result.recordings == () and not list((tmp_path / "out").rglob("*.rrd"))
    assert not (tmp_path / "out" / "recordings").exists()
    assert result.command.endswith("--quick --no-recordings")
    assert not (tmp_path / "out" / "report.md").exists()  # the run writes no report
    written = write_report(result)
    assert written == {
        "markdown": tmp_path / "out" / "report.md",
        "json": tmp_path / "out" / "results.json",
    }
    data = json.loads(written["json"].read_text())
    assert data["files"]["report"] == "report.md" and data["files"]["recordings"] == []
    page = written["markdown"].read_text()
    assert f"`{RECOMMENDED.recipe}`" in page and "recordings/" not in page
    try:  # the same seed, recorded (needs the real datasets, which scenarios do not use)
        recorded = json.loads((request.getfixturevalue("demo") / "results.json").read_text())
    except pytest.skip.Exception:
        return
    f1 = [(s["scenario"], s["reform_f1"], s["gcff_f1"]) for s in data["scenarios"]]
    assert f1 == [(s["scenario"], s["reform_f1"], s["gcff_f1"]) for s in recorded["scenarios"]]
    assert any(s["reform_f1"] is not None for s in data["scenarios"])


def test_budgets() -> None:
    assert QUICK.scenario_s < FULL.scenario_s
    # The demo trains on the recipe the sim-to-real experiment recommends, at a smaller budget.
    wanted = recipe(RECOMMENDED.recipe).sources
    for budget in (FULL, QUICK):
        assert [s.scenario for s in budget.train] == [s.scenario for s in wanted]
        assert [s.annotation for s in budget.train] == [s.annotation for s in wanted]
        assert all(s.episodes <= w.episodes for s, w in zip(budget.train, wanted, strict=True))
    assert FULL.stress_grid == "small"


def test_the_real_datasets_are_found_without_a_flag(tmp_path, monkeypatch, capsys) -> None:
    """No --datasets: $REFORM_SIM_DATASETS, else ../shared/datasets beside the working folder."""
    from sim.cli._common import default_datasets

    clone = tmp_path / "clone"
    clone.mkdir()
    monkeypatch.chdir(clone)
    monkeypatch.delenv("REFORM_SIM_DATASETS", raising=False)
    assert default_datasets() is None
    (tmp_path / "shared" / "datasets").mkdir(parents=True)
    assert default_datasets() == "../shared/datasets"
    monkeypatch.setenv("REFORM_SIM_DATASETS", "/elsewhere")
    assert default_datasets() == "/elsewhere"
    # The demo then reads that folder: a missing one is named in the error.
    assert main(["demo", "--quick", "--out", str(tmp_path / "o")]) == 2
    assert "/elsewhere is not a folder" in capsys.readouterr().err

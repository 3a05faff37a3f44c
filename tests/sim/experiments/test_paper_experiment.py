"""Splits by time, the paper's experiment, and the REFORM commands."""

from __future__ import annotations

import json

import numpy as np
import pytest
from toy_scenes import toy_frames

from reform import Dataset, Frame, time_blocks, time_split, write_parquet
from reform.datasets import load_babble, load_salsa
from sim.cli import main
from sim.experiments.paper import (
    BABBLE,
    PAPER_BABBLE,
    PAPER_TABLE_I,
    SALSA_TEST,
    SALSA_TRAIN,
    paper_experiment,
    random_split,
)
from sim.experiments.paper_report import to_markdown


def frame(t: float, sequence: str, annotated: bool = True) -> Frame:
    return Frame(
        ids=[1, 2],
        position=[[0.0, 0.0], [1.0, 0.0]],
        yaw=[0.0, np.pi],
        groups=((1, 2),) if annotated else None,
        time=t,
        sequence=sequence,
    )


def test_time_split_cuts_each_sequence_by_time():
    frames = [frame(t, "a") for t in (5, 0, 1, 4, 2, 3, 6, 7, 8, 9)]  # out of order
    frames += [frame(t, "b") for t in range(5)]
    frames.append(frame(2.5, "b", annotated=False))
    train, test = time_split(frames, 0.6)
    assert sorted(f.time for f in train if f.sequence == "a") == [0, 1, 2, 3, 4, 5]
    assert sorted(f.time for f in test if f.sequence == "a") == [6, 7, 8, 9]
    # 0.6 * 5 = 3 frames of b train; the unannotated frame at 2.5 s sits before the cut (3 s)
    assert sorted(f.time for f in train if f.sequence == "b") == [0, 1, 2, 2.5]
    assert sorted(f.time for f in test if f.sequence == "b") == [3, 4]
    assert [f.time for f in train if f.sequence == "a"] == [5, 0, 1, 4, 2, 3]  # input order kept
    assert max(f.time for f in train if f.sequence == "a") < min(
        f.time for f in test if f.sequence == "a"
    )


def test_time_split_rounds_halves_up_and_checks_its_fraction():
    train, test = time_split([frame(t, "s") for t in range(5)], 0.5)  # 2.5 -> 3
    assert len(train) == 3 and len(test) == 2
    for bad in (0.0, 1.0, -0.1, 1.5, True):
        with pytest.raises(ValueError, match="train_fraction must lie in \\(0, 1\\)"):
            time_split([frame(0, "s")], bad)
    with pytest.raises(TypeError, match="time_split takes reform.Frame objects, got str"):
        time_split(["frame"])


def test_time_blocks_are_stretches_of_time_per_sequence():
    frames = [frame(t, "a") for t in (9, 3, 0, 6, 1, 2, 4, 5, 7, 8)] + [
        frame(t, "b") for t in range(5)
    ]
    blocks = time_blocks(frames, 5)
    by_time = {f.time: b for f, b in zip(frames[:10], blocks[:10], strict=True)}
    assert [by_time[t] for t in range(10)] == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4]
    assert blocks[10:].tolist() == [0, 1, 2, 3, 4]
    with pytest.raises(ValueError, match="n_blocks must be an integer >= 2, got 1"):
        time_blocks(frames, 1)


def test_random_split_is_seeded():
    frames = toy_frames(0, 20)
    first = random_split(frames, 0.6, seed=3)
    assert first == random_split(frames, 0.6, seed=3)
    assert len(first[0]) == 12 and len(first[1]) == 8
    assert {f.time for f in first[0]} | {f.time for f in first[1]} == set(range(20))


SMALL_GRIDS = {
    "weighted-knn": {"knn__n_neighbors": (5, 15)},
    "bagged-trees": {"estimator__min_samples_leaf": (20,)},
    "logistic-regression": {"logreg__C": (1.0,)},
}


@pytest.fixture(scope="module")
def small_experiment(salsa_dir, babble_dir):
    salsa = load_salsa(salsa_dir)
    # 40 frames of each session keep the test quick; the protocol is the same as the full run.
    keep = []
    for name in ("session1", "session2"):
        keep += [f for f in salsa.annotated() if f.sequence == name][:40]
    subset = Dataset(frames=tuple(keep), name="salsa", source=salsa.source)
    return paper_experiment(
        subset, load_babble(babble_dir), grids=SMALL_GRIDS, n_folds=3, diagnostics=True
    )


def test_paper_experiment_scores_every_detector_on_every_part(small_experiment):
    e = small_experiment
    assert e.frames == {SALSA_TRAIN: 48, SALSA_TEST: 32, BABBLE: 99}
    assert {(r["detector"], r["dataset"]) for r in e.results} == {
        (d, p)
        for d in (
            "majority",
            "REFORM Weighted KNN",
            "REFORM Bagged Trees",
            "REFORM Logistic Regression",
        )
        for p in (SALSA_TEST, BABBLE)
    }
    assert all(r["dataset"] == SALSA_TRAIN for r in e.train_results)
    majority = e.result("majority", SALSA_TEST)
    assert majority["2/3"]["precision"] == 1.0 and majority["2/3"]["recall"] == 0.0
    for name in ("weighted-knn", "bagged-trees", "logistic-regression"):
        test = e.result(name, SALSA_TEST)
        assert test["frames"] == 32
        assert test["2/3"]["f1"] > 0.5  # REFORM finds most groups even trained on 48 frames
        assert test["2/3"]["f1"] >= test["1"]["f1"]
        assert 0.8 < test["classifier_pairwise_accuracy"] <= 1.0
        assert e.result(name, BABBLE)["frames"] == 99
    assert [t.classifier for t in e.tuning] == [
        "weighted-knn",
        "bagged-trees",
        "logistic-regression",
    ]
    kinds = {(d["classifier"], d["split"], d["features"]) for d in e.diagnostics}
    assert ("bagged-trees", "random split, session 1 (paper's kind)", "as defined") in kinds
    assert ("logistic-regression", "time split, both sessions (ours)", "without wrapping") in kinds


def test_paper_experiment_writes_markdown_and_json(small_experiment):
    markdown = to_markdown(small_experiment, command="reform-sim experiment paper --out x")
    assert "reform-sim experiment paper --out x" in markdown
    assert "## SALSA (Table I), T = 2/3" in markdown
    assert "## Babble (trained on SALSA only)" in markdown
    assert "## Where our figures differ from the paper's, and why" in markdown
    f1_test = PAPER_TABLE_I["bagged-trees"][6]
    assert f"({f1_test:.1f})" in markdown  # the paper's figure beside ours
    assert f"({PAPER_BABBLE['weighted-knn'][2]:.1f})" in markdown
    data = json.loads(json.dumps(small_experiment.to_json(command="c"), allow_nan=False))
    assert data["kind"] == "reform-sim/paper-experiment"
    assert data["split"]["frames"][SALSA_TEST] == 32
    assert {r["kind"] for r in data["results"]} == {"reform-sim/evaluation"}


def test_paper_experiment_rejects_unknown_classifiers(salsa_dir, babble_dir):
    with pytest.raises(ValueError, match="classifiers must be among .* got 'svm'"):
        paper_experiment(
            Dataset(frames=(), name="s"), Dataset(frames=(), name="b"), classifiers=("svm",)
        )


@pytest.fixture
def toy_dataset(tmp_path):
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 50)), name="toy", source="toy_scenes"), path)
    return path


def test_train_then_evaluate_and_detect_from_the_model_file(toy_dataset, tmp_path, capsys):
    model = tmp_path / "model.skops"
    args = ["train", "--data", str(toy_dataset), "--classifier", "logistic-regression"]
    assert main([*args, "--frames", "train", "--out", str(model)]) == 0
    assert "trained REFORM (logistic-regression) on 30 frames of toy" in capsys.readouterr().out
    scores = tmp_path / "scores.json"
    code = main(
        ["evaluate", "--model", str(model), "--data", str(toy_dataset), "--json", str(scores)]
    )
    assert code == 0
    result = json.loads(scores.read_text())
    assert result["detector"] == "reform" and result["frames"] == 50
    assert result["2/3"]["f1"] > 0.9
    groups = tmp_path / "groups.json"
    code = main(["detect", "--model", str(model), "--data", str(toy_dataset), "--out", str(groups)])
    assert code == 0
    detections = json.loads(groups.read_text())
    assert detections["detector"] == "reform"
    assert detections["detector_params"]["features"] == ["distance", "effort_angle"]
    assert len(detections["frames"]) == 50


def test_train_can_tune(toy_dataset, tmp_path, capsys):
    out = tmp_path / "tuned.skops"
    args = ["train", "--data", str(toy_dataset), "--classifier", "weighted-knn", "--tune"]
    assert main([*args, "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "CV pairwise accuracy" in captured.err
    assert "trained REFORM (weighted-knn, {'n_neighbors':" in captured.out


def test_commands_report_bad_input(toy_dataset, tmp_path, capsys, monkeypatch):
    assert main(["evaluate", "--data", str(toy_dataset)]) == 2
    assert "give --detector NAME, or --model MODEL" in capsys.readouterr().err
    assert main(["evaluate", "--detector", "reform", "--data", str(toy_dataset)]) == 2
    assert "--detector reform needs --model MODEL" in capsys.readouterr().err
    missing = tmp_path / "missing.skops"
    args = ["detect", "--model", str(missing), "--data", str(toy_dataset), "--out", "x"]
    assert main(args) == 2
    assert "does not exist" in capsys.readouterr().err
    args = ["train", "--data", str(toy_dataset), "--out", str(tmp_path / "m.skops")]
    assert main([*args, "--train-fraction", "1.5"]) == 2
    assert "--train-fraction must lie in (0, 1)" in capsys.readouterr().err
    assert main([*args, "--features", "distance,gaze"]) == 2
    assert "features must be among" in capsys.readouterr().err
    assert main([*args, "--threshold", "2"]) == 2
    assert "--threshold must be a probability in (0, 1), got 2" in capsys.readouterr().err
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "none"))  # no datasets anywhere
    monkeypatch.setenv("REFORM_SIM_DATA", str(tmp_path / "cache"))
    assert main(["experiment", "paper", "--out", str(tmp_path / "x")]) == 2
    assert "reform-sim datasets fetch salsa" in capsys.readouterr().err
    assert not (tmp_path / "m.skops").exists()

"""The GCFF comparison experiment (small tuning grid), library and command."""

from __future__ import annotations

import json

import pytest

from reform import Gcff, evaluate, time_split
from sim.experiments.gcff import BABBLE, SALSA_TEST, gcff_comparison
from sim.experiments.gcff_report import to_markdown

GRID = {"stride_grid": (0.7,), "mdl_grid": (1.0, 3.0)}


@pytest.fixture(scope="module")
def comparison(salsa_dataset, babble_dataset):
    return gcff_comparison(salsa_dataset, babble_dataset, **GRID)


def test_rows_datasets_and_split(comparison, salsa_dataset, babble_dataset):
    train, test = time_split(salsa_dataset.annotated())
    assert comparison.frames == {
        "salsa-train": len(train),
        "salsa-test": len(test),
        "babble": len(babble_dataset.annotated()),
    }
    assert [(r["detector"].split(" (")[0], r["dataset"]) for r in comparison.results] == [
        ("GCFF, paper", SALSA_TEST),
        ("GCFF, reference default", SALSA_TEST),
        ("GCFF, tuned on SALSA train", SALSA_TEST),
        ("GCFF, paper numbers with units ignored", SALSA_TEST),
        ("Majority", SALSA_TEST),
        ("GCFF, paper", BABBLE),
        ("GCFF, reference default", BABBLE),
        ("GCFF, tuned on SALSA train", BABBLE),
        ("GCFF, paper numbers with units ignored", BABBLE),
        ("Majority", BABBLE),
    ]
    paper = comparison.results[0]
    assert (paper["detector_params"]["stride"], paper["detector_params"]["mdl"]) == (0.7, 3.0)
    expected = evaluate(test, Gcff(stride=0.7, mdl=3.0).predict(test)).at("2/3")
    assert paper["2/3"]["f1"] == pytest.approx(expected.f1)


def test_tuned_on_training_frames_only(comparison, salsa_dataset):
    train, _ = time_split(salsa_dataset.annotated())
    search = comparison.tuning
    assert search.n_frames == len(train) and search.f1.shape == (2,)
    tuned = [r for r in comparison.results if r["detector"].startswith("GCFF, tuned")]
    for result in tuned:
        params = result["detector_params"]
        assert (params["stride"], params["mdl"]) == (search.best_stride, search.best_mdl)
    assert search.best_f1 == max(search.f1)


def test_added_results_must_share_the_frames(comparison):
    ours = comparison.results[0]
    other = dict(ours, detector="Other")
    majority = dict(comparison.results[4], detector="majority")
    bigger = comparison.with_results([other, majority, other])
    assert bigger.results[-1]["detector"] == "Other"
    assert len(bigger.results) == len(comparison.results) + 1  # duplicates left out
    assert any("REFORM's classifiers are not in this run" in n for n in comparison.all_notes())
    assert bigger.all_notes() == ()
    assert comparison.summary() == ()
    (line,) = bigger.summary()  # only SALSA test got an added row
    paper, tuned = comparison.results[0]["2/3"]["f1"], comparison.results[2]["2/3"]["f1"]
    assert line == (
        f"SALSA test split: GCFF with the paper's setting {100 * paper:.1f}, GCFF tuned on SALSA "
        f"train {100 * tuned:.1f}; the added detectors (Other) {100 * paper:.1f}. The paper's "
        "figures here: GCFF 64.2, its classifiers 74.8-81.2."
    )
    with pytest.raises(ValueError, match="must be scored on the same"):
        comparison.with_results([dict(other, frames=ours["frames"] + 1)])
    with pytest.raises(ValueError, match="dataset must be 'salsa-test' or 'babble'"):
        comparison.with_results([dict(other, dataset="salsa")])


def test_markdown_and_json(comparison):
    command = "reform-sim experiment gcff --salsa S --babble B --out X"
    markdown = to_markdown(comparison, command=command)
    assert command in markdown
    assert "## SALSA test split" in markdown and "## Babble" in markdown
    assert "30,000 cm² = 3.0 m²" in markdown
    data = json.loads(json.dumps(comparison.to_json(command=command), allow_nan=False))
    assert data["kind"] == "reform-sim/gcff-comparison"
    assert data["command"] == command
    assert len(data["tuning"]["grid"]) == 2
    assert len(data["results"]) == 10


def test_command_writes_markdown_and_json(tmp_path, salsa_dataset, salsa_dir, babble_dir):
    from reform import Majority
    from sim.cli import main

    # Another detector's evaluation on the same frames joins the tables.
    _, test = time_split(salsa_dataset.annotated())
    other = evaluate(test, Majority().predict(test)).to_json(
        detector="Other detector", dataset=SALSA_TEST
    )
    other_json = tmp_path / "other.json"
    other_json.write_text(json.dumps({"results": [other]}))
    out = tmp_path / "results" / "gcff-comparison"
    args = ["--data", f"salsa={str(salsa_dir)}", "--data", f"babble={str(babble_dir)}"]
    args += ["--stride-grid", "0.7", "--mdl-grid", "1", "--with-results", str(other_json)]
    assert main(["experiment", "gcff", *args, "--out", f"{out}.md"]) == 0
    written = json.loads(out.with_suffix(".json").read_text())
    assert "--stride-grid 0.7 --mdl-grid 1 --with-results" in written["command"]
    assert written["results"][-1]["detector"] == "Other detector"
    assert written["notes"] == []
    assert "| Other detector" in out.with_suffix(".md").read_text()

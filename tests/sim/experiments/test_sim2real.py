"""Sim-to-real: candidates chosen on SALSA's training split and simulation, scored on real data."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import kendalltau

from reform.datasets import load_dataset
from reform.features import FEATURE_SETS
from reform.metrics import T_TWO_THIRDS, evaluate
from reform.persistence import load_model, model_info
from sim.cli import main
from sim.experiments.sim2real import (
    RECIPES,
    RECOMMENDED,
    SIM_PARTY,
    Candidate,
    Recipe,
    candidates,
    choice_shares,
    sim_to_real,
)
from sim.experiments.sim2real_report import (
    calibration_figure,
    rank_figure,
    sim2real_figure,
    to_markdown,
)
from sim.experiments.synthetic import SyntheticSource

GRIDS = {"stride_grid": (0.6, 0.7), "mdl_grid": (1.0, 3.0)}
OPTIONS = ({}, {"features": "relative", "reconstruction": "correlation"})
TINY = (
    Recipe(
        "party",
        (SyntheticSource("mingle", episodes=1, duration=60.0, rate=0.5),),
        "one short party",
    ),
    Recipe(
        "coded",
        (
            SyntheticSource(
                "mingle-randomised",
                episodes=1,
                duration=60.0,
                rate=0.5,
                options={"people_max": 12},
                annotation={"directions": 8},
            ),
        ),
        "one short randomised party, orientation coded in 8 directions",
    ),
)


@pytest.fixture(scope="module")
def coffeebreak(shared_datasets):
    return load_dataset(shared_datasets / "coffeebreak")


def _run(real, root, **kwargs):
    return sim_to_real(
        real,
        synthetic_root=root,
        recipes=TINY,
        classifiers=("logistic-regression",),
        option_sets=OPTIONS,
        party_episodes=1,
        seed=3,
        gcff_grids=GRIDS,
        progress_bars=False,
        **kwargs,
    )


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, salsa_dataset, babble_dataset, coffeebreak):
    root = tmp_path_factory.mktemp("synthetic")
    model = tmp_path_factory.mktemp("out") / "recommended.skops"
    real = {"salsa": salsa_dataset, "babble": babble_dataset, "coffeebreak": coffeebreak}
    return _run(real, root, out_model=model), root, model, real


def test_the_choice_is_the_best_selection_score(tiny) -> None:
    result, _, _, _ = tiny
    assert [s["label"] for s in result.selection] == [
        c.label for c in candidates(TINY, ("logistic-regression",), OPTIONS)
    ]
    for entry in result.selection:
        validation = list(entry["validation_f1"].values())
        views = entry["salsa_views_f1"]
        assert list(views) == [
            "salsa (training split)",
            "salsa (training split), positions x0.6",
            "salsa (training split), positions x1.6",
            "salsa (training split), 4 directions",
        ]
        assert entry["salsa_train_f1"] == views["salsa (training split)"]
        salsa = np.mean(list(views.values()))
        assert entry["score"] == pytest.approx((salsa + np.mean(validation)) / 2)
        assert set(entry["validation_f1"]) == {
            "validation: mingle",
            "validation: mingle-randomised",
        }
    best = max(result.selection, key=lambda e: e["score"])
    assert [e["chosen"] for e in result.selection].count(True) == 1
    assert best["chosen"] and best["label"] == result.recommended.label


def test_choice_shares_count_the_resamples_each_candidate_wins() -> None:
    scores = np.array(
        [
            [0.8, 0.7, 0.5, 0.6],
            [0.7, 0.9, 0.5, 0.6],  # ties (columns 2 and 3) go to the first candidate
            [0.1, 0.1, 0.1, 0.1],
        ]
    )
    assert choice_shares(scores).tolist() == [0.75, 0.25, 0.0]
    with pytest.raises(ValueError, match=r"scores must be a \(candidates, resamples\) array"):
        choice_shares(np.zeros((3, 0)))


def test_how_sure_the_choice_is(tiny) -> None:
    result, _, _, _ = tiny
    stability = result.choice_stability
    assert sum(stability.values()) == pytest.approx(1.0)
    assert set(stability) <= {s["label"] for s in result.selection}
    assert all(0.0 < share <= 1.0 for share in stability.values())
    assert result.to_json()["choice_stability"] == dict(stability)
    markdown = to_markdown(result, command="reform-sim experiment sim2real", figures=())
    own = stability.get(result.recommended.label, 0.0)
    shown = "< 1 %" if 0.0 < own < 0.005 else f"{100 * own:.0f} %"
    assert f"The recommended candidate has it in {shown} of the resamples." in markdown


def test_the_choice_never_sees_a_scored_dataset(tiny, salsa_dataset, tmp_path) -> None:
    """Without Babble and CoffeeBreak the candidates' selection figures and the choice are the
    same: only SALSA's training split and simulation chose. The second run is also the
    determinism check: with the same seed it gives every figure the two runs share, bit for
    bit (the selection, how sure the choice is, every score on SALSA's test split and its
    interval)."""
    result, root, _, _ = tiny
    alone = _run({"salsa": salsa_dataset}, root)
    assert alone.selection == result.selection
    assert alone.recommended == result.recommended
    assert alone.choice_stability == result.choice_stability
    assert alone.datasets == ("salsa (test split)",)
    salsa = {"salsa (test split)", SIM_PARTY}
    shared = [s for s in result.scores if s.dataset in salsa and s.role != "leave-one-out"]
    assert len(shared) > len(result.selection)
    assert [s for s in alone.scores if s.dataset in salsa and s.role != "leave-one-out"] == shared


def test_every_real_dataset_is_scored_beside_the_baselines(tiny) -> None:
    result, _, _, real = tiny
    assert result.datasets == ("salsa (test split)", "babble", "coffeebreak")
    roles = {s.role for s in result.scores}
    assert roles == {
        "recommended",
        "candidate",
        "salsa-trained",
        "gcff-one",
        "gcff-own",
        "leave-one-out",
    }
    for detector in result.detectors("recommended", "salsa-trained", "gcff-one", "gcff-own"):
        assert {s.dataset for s in result.scores if s.detector == detector} >= set(result.datasets)
    own = {s.dataset: s.note for s in result.scores if s.role == "gcff-own"}
    assert own["coffeebreak"] == "settings shipped with the dataset"
    assert own["salsa (test split)"].startswith("grid search on its training split")
    assert own["babble"].startswith("grid search on its own scored frames")
    # A score is the field's protocol on the dataset's frames: GCFF re-run by hand.
    gcff = result.detectors("gcff-one")[0]
    frames = real["babble"].annotated()
    from reform.gcff import Gcff

    by_hand = evaluate(frames, Gcff(stride=0.7, mdl=3.0).predict(frames)).at(T_TWO_THIRDS)
    assert result.score(gcff, "babble").f1 == pytest.approx(by_hand.f1)
    for score in result.scores:
        low, high = score.f1_interval
        assert low <= score.f1 + 1e-9 and score.f1 <= high + 1e-9
    leave = result.detectors("leave-one-out")[0]
    assert {s.dataset for s in result.scores if s.detector == leave} == set(result.datasets)


def test_the_saved_model_is_the_recommended_one(tiny) -> None:
    result, _, model_path, real = tiny
    model = load_model(model_path)
    frames = real["coffeebreak"].annotated()
    f1 = evaluate(frames, model.predict(frames)).at(T_TWO_THIRDS).f1
    assert f1 == pytest.approx(result.score(result.recommended.label, "coffeebreak").f1)


def test_rank_agreement_is_kendalls_tau_of_the_rows(tiny) -> None:
    result, _, _, _ = tiny
    rank = result.rank
    assert len(rank.detectors) == len(TINY) * len(OPTIONS) + 2  # candidates, SALSA-trained, GCFF
    assert rank.tau == pytest.approx(kendalltau(rank.simulated, rank.real).statistic)
    for name, sim, real in zip(rank.detectors, rank.simulated, rank.real, strict=True):
        assert sim == pytest.approx(result.score(name, SIM_PARTY).f1)
        assert real == pytest.approx(result.mean_f1(name))
    low, high = rank.interval
    assert -1.0 <= low <= high <= 1.0
    field = result.rank_field
    assert field.detectors == rank.detectors and field.real == rank.real
    validation = ("validation: mingle", "validation: mingle-randomised")
    for name, sim in zip(field.detectors, field.simulated, strict=True):
        if name in {s["label"] for s in result.selection}:
            (entry,) = [s for s in result.selection if s["label"] == name]
            assert sim == pytest.approx(np.mean([entry["validation_f1"][v] for v in validation]))
    assert field.tau == pytest.approx(kendalltau(field.simulated, field.real).statistic)
    recorded = result.rank_recorded
    assert recorded.detectors == rank.detectors and recorded.real == rank.real
    assert recorded.tau == pytest.approx(kendalltau(recorded.simulated, recorded.real).statistic)
    # The party's four views: as recorded (the default party itself), rescaled twice, recoded.
    document = result.to_json()
    assert [r["benchmark"] for r in document["rank_agreement"]] == [
        "simulated party",
        "simulated field",
        "simulated party, recorded as the field's datasets",
    ]
    # The reference: each real dataset against the mean of the others, over the same detectors.
    between = result.rank_between_real
    assert [r.benchmark for r in between] == list(result.datasets)
    assert len(result.datasets) > 1
    for reference in between:
        others = [d for d in result.datasets if d != reference.benchmark]
        assert reference.detectors == rank.detectors
        for name, own, rest in zip(
            reference.detectors, reference.simulated, reference.real, strict=True
        ):
            assert own == pytest.approx(result.score(name, reference.benchmark).f1)
            assert rest == pytest.approx(np.mean([result.score(name, d).f1 for d in others]))
        assert reference.tau == pytest.approx(
            kendalltau(reference.simulated, reference.real).statistic, nan_ok=True
        )
    assert [r["benchmark"] for r in document["rank_between_real"]] == list(result.datasets)
    # GCFF's stride is in metres: rescaled parties score it otherwise than the party itself.
    gcff = rank.detectors.index(result.detectors("gcff-one")[0])
    assert recorded.simulated[gcff] != pytest.approx(rank.simulated[gcff])


def test_rank_agreement_over_the_compared_detectors_and_on_salsas_training_split(tiny) -> None:
    result, _, _, _ = tiny
    rank, gcff_one = result.rank, result.detectors("gcff-one")[0]
    compared = result.rank_compared
    assert compared.detectors == (
        result.recommended.label,
        *result.detectors("salsa-trained"),
        gcff_one,
    )
    party = {d: s for d, s in zip(rank.detectors, rank.simulated, strict=True)}
    assert compared.simulated == tuple(party[d] for d in compared.detectors)
    assert compared.tau == pytest.approx(
        kendalltau(compared.simulated, compared.real).statistic, nan_ok=True
    )
    # SALSA's training split ranks only the detectors that never trained on it.
    train = result.rank_salsa_train
    assert train.benchmark == "salsa (training split)"
    assert set(train.detectors) == set(rank.detectors) - set(result.detectors("salsa-trained"))
    on_train = {s["label"]: s["salsa_train_f1"] for s in result.selection}
    for name, f1, real in zip(train.detectors, train.simulated, train.real, strict=True):
        assert real == pytest.approx(result.mean_f1(name))
        if name != gcff_one:
            assert f1 == pytest.approx(on_train[name])
    assert 0.0 < train.simulated[train.detectors.index(gcff_one)] <= 1.0
    # ... and against SALSA's test split alone: the rest of the same recording.
    halves = result.rank_salsa_halves
    assert halves.detectors == train.detectors and halves.simulated == train.simulated
    for name, test in zip(halves.detectors, halves.real, strict=True):
        assert test == pytest.approx(result.score(name, "salsa (test split)").f1)
    assert halves.tau == pytest.approx(
        kendalltau(halves.simulated, halves.real).statistic, nan_ok=True
    )
    document = result.to_json()
    assert document["rank_compared"]["tau"] == pytest.approx(compared.tau, nan_ok=True)
    assert document["rank_salsa_train"]["benchmark"] == "salsa (training split)"
    markdown = to_markdown(result, command="reform-sim experiment sim2real", figures=())
    assert f"Kendall's tau **{compared.tau:.2f}**" in markdown
    assert f"tau **{train.tau:.2f}**" in markdown
    assert f"rest of the same recording, with tau **{halves.tau:.2f}**" in markdown
    verdict = "at or above" if halves.tau >= 0.8 else "below"
    assert f"two parts of one recording agree {verdict} the goal's 0.8" in markdown
    assert document["rank_salsa_halves"]["tau"] == pytest.approx(halves.tau, nan_ok=True)


def test_goals_follow_from_the_scores(tiny) -> None:
    result, _, _, _ = tiny
    goals = {g.name: g for g in result.goals}
    ours = result.mean_f1(result.recommended.label)
    one = result.mean_f1(result.detectors("gcff-one")[0])
    own = result.mean_f1(result.detectors("gcff-own")[0])
    assert goals["mean over the real datasets vs GCFF, one setting"].met == (ours >= one + 0.05)
    assert goals["moonshot: mean vs GCFF, each dataset's own settings"].met == (ours >= own)
    assert goals["rank agreement, simulation vs real"].met == (result.rank.tau >= 0.8)
    salsa = "salsa (test split)"
    best = max(result.score(d, salsa).f1 for d in result.detectors("salsa-trained"))
    ours_salsa = result.score(result.recommended.label, salsa).f1
    assert goals["SALSA's test split"].met == (ours_salsa >= best - 0.02)


def test_report(tiny, tmp_path) -> None:
    # (the same seed's second run is checked in test_the_choice_never_sees_a_scored_dataset)
    result, _, _, _ = tiny
    document = result.to_json(command="reform-sim experiment sim2real")
    json.dumps(document, allow_nan=False)
    paths = [
        draw(result, tmp_path / name)
        for draw, name in (
            (sim2real_figure, "s.png"),
            (rank_figure, "r.png"),
            (calibration_figure, "c.png"),
        )
    ]
    assert all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in paths)
    markdown = to_markdown(result, command="reform-sim experiment sim2real", figures=["s.png"])
    for dataset in result.datasets:
        assert f"## {dataset}" in markdown
    assert f"**Recommended: {result.recommended.label}**" in markdown
    assert "Kendall's tau" in markdown and "recommended.skops" in markdown


def test_salsa_views_are_the_training_split_recorded_otherwise(salsa_dataset) -> None:
    from reform.splits import time_split
    from sim.experiments.sim2real import salsa_views

    train, _ = time_split(salsa_dataset.annotated(), 0.6)
    views = salsa_views(train[:20])
    recorded, small, large, coded = views.values()
    assert recorded == tuple(train[:20])
    for a, b, c, d in zip(recorded, small, large, coded, strict=True):
        assert np.allclose(b.position, 0.6 * a.position) and np.allclose(
            c.position, 1.6 * a.position
        )
        assert b.groups == a.groups == d.groups and np.array_equal(d.position, a.position)
        steps = np.round(d.yaw / (np.pi / 2))
        assert np.allclose(np.cos(d.yaw - steps * np.pi / 2), 1.0)  # multiples of 90 degrees


def test_the_documented_recipes_and_choice() -> None:
    """RECOMMENDED is what the documented run chose (docs/results/sim2real.json)."""
    from pathlib import Path

    document = json.loads(
        (Path(__file__).parents[3] / "docs" / "results" / "sim2real.json").read_text()
    )
    assert document["recommended"]["label"] == RECOMMENDED.label
    assert [r["name"] for r in document["recipes"]] == [r.name for r in RECIPES]
    chosen = [s for s in document["selection"] if s["chosen"]]
    assert [s["label"] for s in chosen] == [RECOMMENDED.label]
    assert max(s["score"] for s in document["selection"]) == chosen[0]["score"]
    # The documented model file is that candidate.
    info = model_info(Path(__file__).parents[3] / "docs" / "results" / "recommended.skops")
    assert info["features"] == list(FEATURE_SETS["relative"])


def test_bad_input(salsa_dataset, babble_dataset, tmp_path) -> None:
    with pytest.raises(ValueError, match="the experiment needs SALSA"):
        sim_to_real({"babble": babble_dataset}, synthetic_root=tmp_path)
    with pytest.raises(ValueError, match="classifiers must be among"):
        sim_to_real({"salsa": salsa_dataset}, synthetic_root=tmp_path, classifiers=("svm",))
    with pytest.raises(ValueError, match="party_episodes must be an int >= 1, got 0"):
        sim_to_real({"salsa": salsa_dataset}, synthetic_root=tmp_path, party_episodes=0)
    with pytest.raises(ValueError, match="classifier must be one of"):
        Candidate("scenes", "svm")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--episodes-scale", "0"], "--episodes-scale must be a finite number > 0, got 0.0"),
        (["--episodes-scale", "inf"], "--episodes-scale must be a finite number > 0, got inf"),
        (["--classifiers", "svm"], "--classifiers must be among"),
        (["--data", "=x"], "--data =x: expected NAME=PATH, got an empty side"),
    ],
)
def test_cli_bad_input(argv, message, tmp_path, capsys) -> None:
    data = ["--data", "salsa=/nonexistent/s"]
    assert main(["experiment", "sim2real", "--out", str(tmp_path), *data, *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_cli_needs_salsa(tmp_path, babble_dir, capsys) -> None:
    argv = ["experiment", "sim2real", "--out", str(tmp_path / "o"), "--data", str(babble_dir)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "the experiment needs SALSA" in err and "got babble" in err
    assert err.count("\n") == 1 and not (tmp_path / "o").exists()


def test_cli_without_datasets_says_how_to_fetch_them(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "none"))
    monkeypatch.setenv("REFORM_SIM_DATA", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    assert main(["experiment", "sim2real", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "reform-sim datasets fetch salsa" in err and err.count("\n") == 1


def test_cli_reads_a_folder_of_datasets(shared_datasets) -> None:
    from sim.cli.experiment_sim2real import load_named

    named = load_named([str(shared_datasets)])
    assert {"salsa", "babble", "coffeebreak", "synth"} <= set(named)
    assert named["salsa"].name.lower().startswith("salsa")


def _tiny_dante(folder: Path) -> None:
    folder.mkdir(parents=True)
    (folder / "features.txt").write_text("0.0 ID_001 1.0 1.0 0.0 ID_002 2.0 1.0 3.14\n")
    (folder / "group_names.txt").write_text("0.0 < ID_001 ID_002 > \n")


def test_cli_scores_a_recording_once(shared_datasets, tmp_path, capsys) -> None:
    """Both packagings of the Cocktail Party in a folder of datasets: the second is left out,
    with one line saying so; named one by one, both are scored."""
    from sim.cli.experiment_sim2real import load_named

    (tmp_path / "salsa").symlink_to(shared_datasets / "salsa")
    _tiny_dante(tmp_path / "cocktail-party")
    _tiny_dante(tmp_path / "cocktail-party-dante")
    assert set(load_named([str(tmp_path)])) == {"salsa", "cocktail-party"}
    err = capsys.readouterr().err
    assert err == (
        "cocktail-party-dante left out: the same recording as cocktail-party, which is scored "
        "(give --data cocktail-party-dante to score it)\n"
    )
    both = load_named(
        [str(tmp_path / n) for n in ("salsa", "cocktail-party", "cocktail-party-dante")]
    )
    assert set(both) == {"salsa", "cocktail-party", "cocktail-party-dante"}
    assert capsys.readouterr().err == ""


def test_an_undefined_tau_is_said_not_invented() -> None:
    """Every detector tied in simulation: Kendall's tau is undefined, and the JSON says null
    rather than a made-up 0."""
    from sim.experiments.sim2real import RankAgreement, _tau

    tau = _tau(np.array([0.5, 0.5, 0.5]), np.array([0.2, 0.4, 0.9]))
    assert np.isnan(tau)
    rank = RankAgreement(SIM_PARTY, ("a", "b", "c"), (0.5,) * 3, (0.2, 0.4, 0.9), tau, (tau, tau))
    document = rank.to_json()
    assert document["tau"] is None and document["interval"] == [None, None]
    json.dumps(document, allow_nan=False)


def test_the_bootstraps_taus_are_scipys_kendall_tau_b_column_by_column() -> None:
    """`_taus` computes every resample's tau at once: on scores with ties on either side, on
    both sides of one pair, and on one side throughout, each column is scipy's tau-b (NaN where
    scipy says NaN)."""
    from sim.experiments.sim2real import _taus

    rng = np.random.default_rng(5)
    for detectors in (2, 3, 7):
        x = rng.integers(0, 4, size=(detectors, 50)) / 4.0  # coarse: many ties
        y = rng.normal(size=(detectors, 50)).round(1)
        y[:, :5] = 0.3  # every detector tied in these resamples
        taus = _taus(x, y)
        expected = [kendalltau(x[:, b], y[:, b]).statistic for b in range(x.shape[1])]
        np.testing.assert_allclose(taus, expected, rtol=0, atol=1e-12, equal_nan=True)
        assert np.isnan(taus[:5]).all() and np.isfinite(taus[5:]).any()

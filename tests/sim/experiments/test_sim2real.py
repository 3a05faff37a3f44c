"""Sim-to-real: sources, balance, tracker-noise calibration, the experiment on a tiny budget."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from reform.metrics import T_TWO_THIRDS, evaluate
from reform.perturb import Perturbation
from sim.cli import main
from sim.episode import simulate_episode
from sim.experiments.sim2real import (
    BABBLE,
    PAPER_BABBLE_F1,
    SALSA_TEST,
    SyntheticSource,
    balance_pairs,
    calibrate_tracker_noise,
    count_pairs,
    half_training,
    sim_to_real,
    train_reform,
)
from sim.experiments.sim2real_report import sim2real_figure, to_markdown


@pytest.fixture(scope="module")
def party():
    """Two minutes of mingle, one frame every 2 s."""
    return simulate_episode("mingle", seed=5, duration=120.0, rate=0.5).dataset.annotated()


@pytest.fixture(scope="module")
def game():
    return simulate_episode("word-improv", seed=5, duration=200.0, rate=0.5).dataset.annotated()


def test_source_folder_names_its_data() -> None:
    a = SyntheticSource("mingle", episodes=3)
    assert a.folder(0) == SyntheticSource("mingle", episodes=9).folder(0)  # more episodes extend
    assert a.folder(0).startswith("mingle-seed0-")
    assert a.folder(1) != a.folder(0)
    assert SyntheticSource("mingle", episodes=3, options={"people": 12}).folder(0) != a.folder(0)
    assert SyntheticSource("mingle", episodes=3, rate=1.0).folder(0) != a.folder(0)
    with pytest.raises(ValueError, match="episodes must be an int >= 1, got 0"):
        SyntheticSource("mingle", episodes=0)


def test_count_pairs(party) -> None:
    # Hand count: n (n - 1) / 2 per frame.
    assert count_pairs(party) == sum(f.n_people * (f.n_people - 1) // 2 for f in party)
    assert count_pairs(()) == 0


def test_balance_pairs_evens_out_the_sources(party, game) -> None:
    kept = balance_pairs({"mingle": party, "word-improv": game})
    small = min(count_pairs(party), count_pairs(game))
    assert list(kept) == ["mingle", "word-improv"]
    for name, frames in kept.items():
        # Within one frame's worth of pairs of the smallest source.
        most = max(f.n_people * (f.n_people - 1) // 2 for f in frames)
        assert abs(count_pairs(frames) - small) <= most, name
    larger = "mingle" if count_pairs(party) > count_pairs(game) else "word-improv"
    source = party if larger == "mingle" else game
    times = [f.time for f in kept[larger]]
    assert times == sorted(times)  # an even subset, in order
    assert times[0] == source[0].time and times[-1] == source[-1].time  # spans the episode
    assert balance_pairs({"mingle": party, "word-improv": game}) == kept
    with pytest.raises(ValueError, match="every source needs frames with pairs"):
        balance_pairs({"mingle": party, "empty": ()})


def test_calibration_recovers_known_noise(party) -> None:
    """A reference made by perturbing the frames with known noise is matched best by that
    noise (other draws, so not the same numbers)."""
    reference = Perturbation(position_noise=0.1, yaw_noise=0.4).apply_all(
        party, np.random.default_rng(99)
    )
    calibration = calibrate_tracker_noise(
        party, reference, seed=0, position_grid=(0.0, 0.1, 0.3), yaw_grid=(0.0, 0.4, 1.0)
    )
    assert (calibration.position_noise, calibration.yaw_noise) == (0.1, 0.4)
    assert len(calibration.grid) == 9
    ks, total = calibration.ks_at(0.1, 0.4)
    assert len(ks) == 4 and total == pytest.approx(calibration.objective)
    assert all(total <= sum(k) for _, _, k in calibration.grid)
    assert calibration.perturbation() == Perturbation(position_noise=0.1, yaw_noise=0.4)
    data = calibration.to_json()
    assert data["position_noise_m"] == 0.1 and len(data["grid"]) == 9
    with pytest.raises(ValueError, match="not on the calibration grid"):
        calibration.ks_at(0.2, 0.4)
    with pytest.raises(ValueError, match="calibration needs synthetic and reference frames"):
        calibrate_tracker_noise((), reference, seed=0)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, salsa_dataset, babble_dataset):
    """The experiment on a tiny budget: one short episode per source, one classifier."""
    root = tmp_path_factory.mktemp("synthetic")
    sources = (
        SyntheticSource("mingle", episodes=1, duration=90.0, rate=0.5, tracker_noise=True),
        SyntheticSource("word-improv", episodes=1, duration=240.0, rate=0.5),
    )
    result = sim_to_real(
        salsa_dataset,
        babble_dataset,
        synthetic_root=root,
        sources=sources,
        seed=2,
        classifiers=("logistic-regression",),
        gcff_grids={"stride_grid": (0.6, 0.7), "mdl_grid": (1.0, 3.0)},
        diagnostics=False,
        progress_bars=False,
    )
    return result, root


@pytest.mark.slow
def test_ray_backend_gives_the_local_experiment(
    tiny, salsa_dataset, babble_dataset, tmp_path, ray_instance
) -> None:
    """The tiny run again as Ray tasks, on a real local instance, into a fresh folder: the same
    synthetic data (generated by Ray workers) and the same results."""
    from sim.executor import Executor

    result, root = tiny
    with Executor("ray", progress=False) as executor:
        remote = sim_to_real(
            salsa_dataset,
            babble_dataset,
            synthetic_root=tmp_path,
            sources=result.sources,
            seed=2,
            classifiers=("logistic-regression",),
            gcff_grids={"stride_grid": (0.6, 0.7), "mdl_grid": (1.0, 3.0)},
            diagnostics=False,
            progress_bars=False,
            executor=executor,
        )
    for source in result.sources:
        folder = source.folder(2)
        shards = sorted(p.relative_to(root) for p in (root / folder).rglob("*.parquet"))
        assert shards and shards == sorted(
            p.relative_to(tmp_path) for p in (tmp_path / folder).rglob("*.parquet")
        )
        for shard in shards:
            assert (tmp_path / shard).read_bytes() == (root / shard).read_bytes()
    ours, theirs = result.to_json(command="x"), remote.to_json(command="x")
    ours.pop("seconds", None), theirs.pop("seconds", None)
    assert theirs == ours


def test_experiment_rows(tiny) -> None:
    result, _ = tiny
    main_rows = [r for r in result.rows if not r.diagnostic]
    # LR synthetic, LR SALSA-trained, GCFF paper, GCFF tuned, majority, on each test set.
    assert len(main_rows) == 10
    assert {r.dataset for r in main_rows} == {SALSA_TEST, BABBLE}
    assert result.frames[SALSA_TEST] == 458 and result.frames[BABBLE] == 99
    for row in main_rows:
        assert row.result["frames"] == result.frames[row.dataset]
        low, high = row.f1_interval
        assert low <= row.f1() + 1e-9 and row.f1() <= high + 1e-9
    gcff = result.row(classifier=None, training="none", dataset=SALSA_TEST)
    assert gcff.detector.startswith("GCFF, paper")
    assert result.gcff_tuning["stride_m"] in (0.6, 0.7)
    assert result.row(classifier=None, training="salsa-train", dataset=BABBLE).detector.startswith(
        "GCFF, tuned on SALSA train"
    )


def test_synthetic_data_and_noise(tiny) -> None:
    result, root = tiny
    assert result.noise is not None and result.noise.reference == "salsa-train"
    counts = result.training
    assert set(counts) == {"mingle", "word-improv"}
    kept = [c["pairs_kept"] for c in counts.values()]
    assert min(kept) == min(c["pairs_generated"] for c in counts.values())
    for source in result.sources:  # generated as Parquet under the root, with a card
        assert (root / source.folder(2) / "dataset.json").is_file()
    assert result.calibration["mingle"]["reference"] == "salsa-train"
    assert result.calibration["word-improv"]["reference"] == "babble"
    assert set(result.tuning) == {"synthetic", "salsa-train"}


def test_goals_follow_from_the_rows(tiny) -> None:
    result, _ = tiny
    names = [g.name for g in result.goals]
    assert names == [
        "Logistic Regression: SALSA test",
        "Logistic Regression: Babble vs SALSA-trained",
        "Logistic Regression: Babble vs GCFF",
    ]
    synthetic = result.row(
        classifier="logistic-regression", training="synthetic", dataset=SALSA_TEST
    )
    salsa = result.row(classifier="logistic-regression", training="salsa-train", dataset=SALSA_TEST)
    assert result.goals[0].met == (synthetic.f1() >= salsa.f1() - 0.02 - 1e-12)
    babble = result.row(classifier="logistic-regression", training="synthetic", dataset=BABBLE)
    salsa_babble = result.row(
        classifier="logistic-regression", training="salsa-train", dataset=BABBLE
    )
    assert result.goals[1].met == (
        babble.f1() >= PAPER_BABBLE_F1 and babble.f1() > salsa_babble.f1()
    )
    difference, low, high = result.differences[("logistic-regression", SALSA_TEST)]
    assert difference == pytest.approx(synthetic.f1() - salsa.f1())
    assert low <= difference + 1e-9 and difference <= high + 1e-9


def test_cross_period_uses_training_halves_only(tiny, salsa_dataset) -> None:
    from reform import time_split

    result, _ = tiny
    train, _ = time_split(salsa_dataset.annotated(), 0.6)
    earlier, later = time_split(train, 0.5)
    rows = {c.held_out: c for c in result.cross_period}
    assert set(rows) == {"earlier", "later"}
    assert rows["earlier"].frames == len(earlier) and rows["later"].frames == len(later)
    assert rows["earlier"].frames + rows["later"].frames == result.frames["salsa-train"]
    for row in rows.values():
        assert row.classifier == "logistic-regression"
        difference, low, high = row.difference
        assert difference == pytest.approx(row.synthetic - row.salsa)
        assert low <= difference + 1e-9 and difference <= high + 1e-9
        assert 0.0 <= row.salsa <= 1.0 and 0.0 <= row.synthetic <= 1.0
    # The SALSA row of the later half is a model trained on the earlier half, with the
    # hyper-parameters tuned on the training split.
    params = result.tuning["salsa-train"]["logistic-regression"]["best_params"]
    model, _ = train_reform("logistic-regression", earlier, tune=False, params=params)
    assert rows["later"].salsa == evaluate(later, model.predict(later)).at(T_TWO_THIRDS).f1
    # The same model, scored on the test split, is a diagnostic row (never a main row).
    _, test = time_split(salsa_dataset.annotated(), 0.6)
    half_rows = [r for r in result.rows if r.training == half_training("earlier")]
    assert {r.dataset for r in half_rows} == {SALSA_TEST, BABBLE}
    assert all(r.diagnostic and r.classifier == "logistic-regression" for r in half_rows)
    on_test = next(r for r in half_rows if r.dataset == SALSA_TEST)
    assert on_test.f1() == evaluate(test, model.predict(test)).at(T_TWO_THIRDS).f1
    assert not any(r.training == half_training("later") and not r.diagnostic for r in result.rows)


def test_report_files(tiny, tmp_path) -> None:
    result, _ = tiny
    figure = sim2real_figure(result, tmp_path / "s.png")
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    markdown = to_markdown(result, command="reform-sim experiment sim2real --out x", figure="s.png")
    assert "reform-sim experiment sim2real --out x" in markdown
    for heading in (
        "## Goals",
        "## SALSA test split",
        "## Babble",
        "## Tracker noise",
        "## Across periods of SALSA's training split",
    ):
        assert heading in markdown
    data = json.loads(json.dumps(result.to_json(command="c"), allow_nan=False))
    assert data["kind"] == "reform-sim/sim2real"
    assert len(data["rows"]) == len(result.rows)
    assert len(data["goals"]) == 3
    assert len(data["cross_period"]) == 2
    # The half models on the test split: one table row per classifier, whole split beside.
    whole = result.row(classifier="logistic-regression", training="salsa-train", dataset=SALSA_TEST)
    halves = markdown.split("The same half models scored on the SALSA test split")[1]
    row = next(line for line in halves.splitlines() if line.startswith("| Logistic"))
    assert f"{100 * whole.f1():.1f}" in row.split("|")[4]


def test_deterministic_data(tiny, salsa_dataset) -> None:
    """The same seed gives the same calibration on the cached data."""
    result, root = tiny
    from sim.experiments.sim2real import generate_sources

    frames = generate_sources(result.sources, root=root, seed=2, progress=False)
    from reform import time_split

    train, _ = time_split(salsa_dataset.annotated(), 0.6)
    again = calibrate_tracker_noise(frames["mingle"], train, seed=2)
    assert (again.position_noise, again.yaw_noise) == (
        result.noise.position_noise,
        result.noise.yaw_noise,
    )
    assert again.grid == result.noise.grid


def test_bad_input(salsa_dataset, babble_dataset, tmp_path) -> None:
    from sim.experiments.sim2real import generate_sources

    with pytest.raises(ValueError, match="classifiers must be among"):
        sim_to_real(salsa_dataset, babble_dataset, synthetic_root=tmp_path, classifiers=("svm",))
    (tmp_path / "features.txt").write_text("0.2 ID_001 1 2 0 0\n")  # a real dataset's file
    with pytest.raises(ValueError, match=r"expected a folder of generated datasets .*features.txt"):
        generate_sources([SyntheticSource("mingle", episodes=1)], root=tmp_path, seed=0)
    (tmp_path / "features.txt").unlink()
    with pytest.raises(ValueError, match="sources must name each scenario once"):
        source = SyntheticSource("mingle", episodes=1)
        generate_sources([source, dataclasses.replace(source)], root=tmp_path, seed=0)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--episodes-scale", "0"], "--episodes-scale must be a finite number > 0, got 0.0"),
        (["--episodes-scale", "inf"], "--episodes-scale must be a finite number > 0, got inf"),
        (["--classifiers", "svm"], "--classifiers must be among"),
        (["--data", "/nonexistent"], "--data /nonexistent: expected one of salsa, babble"),
    ],
)
def test_cli_bad_input(argv, message, tmp_path, capsys) -> None:
    data = ["--data", "salsa=/nonexistent/s", "--data", "babble=/nonexistent/b"]
    assert main(["experiment", "sim2real", "--out", str(tmp_path), *data, *argv]) == 2
    assert message in capsys.readouterr().err


def test_cli_without_datasets_says_how_to_fetch_them(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("REFORM_SIM_DATASETS", str(tmp_path / "none"))
    monkeypatch.setenv("REFORM_SIM_DATA", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    assert main(["experiment", "sim2real", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "reform-sim datasets fetch salsa" in err and err.count("\n") == 1


def test_nearest_neighbour_quantiles() -> None:
    from reform import Frame
    from sim.experiments.sim2real import nearest_neighbour_quantiles

    # Hand-computed: people at x = 0, 1, 3 m; nearest neighbours 1, 1, 2 m.
    frame = Frame(
        ids=np.array([1, 2, 3]),
        position=np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]]),
        yaw=np.zeros(3),
        groups=((1, 2), (3,)),
    )
    q10, q25, q50 = nearest_neighbour_quantiles([frame])
    assert q50 == pytest.approx(1.0) and q10 == pytest.approx(1.0)
    with pytest.raises(ValueError, match="at least one frame of two or more people"):
        nearest_neighbour_quantiles([])


def test_joint_distances(party) -> None:
    from sim.experiments.sim2real import joint_distances

    assert joint_distances(party, party) == (0.0, 0.0)
    spread = [f.replace(position=f.position * 10.0) for f in party]  # every pair 10 x apart
    tv_in, tv_out = joint_distances(spread, party)
    assert tv_in > 0.9 and 0.0 < tv_out <= 1.0

"""The venue-twins experiment: its measures pinned by hand, and a smoke run end to end."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from reform.frame import Dataset
from sim.experiments.twins import (
    across_seeds,
    agreement,
    goal_figures,
    mmrv,
    noise_floor,
    place_errors,
    run_twins,
)
from sim.experiments.twins_report import scatter_figure, to_markdown
from tests.sim.test_twin import _frames


def test_mmrv_is_the_mean_largest_real_gap_hidden_by_a_wrong_order():
    # hand-computed: reversed order; detector 0 is wrongly above 1 (gap 0.1) and 2 (gap 0.2)
    assert mmrv([0.9, 0.8, 0.7], [0.7, 0.8, 0.9]) == pytest.approx((0.2 + 0.1 + 0.2) / 3)
    assert mmrv([0.9, 0.8, 0.7], [0.95, 0.5, 0.1]) == 0.0  # the same order: nothing hidden


def test_agreement_of_a_perfect_prediction():
    cells = [
        {"dataset": d, "detector": k, "predicted": v, "real": v}
        for d, values in (("a", (0.2, 0.5, 0.9)), ("b", (0.3, 0.6, 0.7)))
        for k, v in zip("xyz", values, strict=True)
    ]
    out = agreement(cells, "predicted", resamples=50)
    assert out["pearson"]["value"] == pytest.approx(1.0)
    assert out["kendall"]["value"] == pytest.approx(1.0)
    assert out["mae"]["value"] == 0.0 and out["mmrv"]["value"] == 0.0


def test_the_noise_floor_grows_with_the_real_scores_spread():
    cells = [
        {"dataset": d, "detector": k, "real": v, "real_sd": 0.0}
        for d, values in (("a", (0.2, 0.5, 0.52, 0.9)), ("b", (0.3, 0.6, 0.61, 0.7)))
        for k, v in zip("wxyz", values, strict=True)
    ]
    exact = noise_floor(cells, draws=200)
    assert exact["mae"]["value"] == 0.0 and exact["mmrv"]["value"] == 0.0
    spread = [dict(c, real_sd=0.04) for c in cells]
    noisy = noise_floor(spread, draws=2000)
    # |N(0, 0.04)| has mean 0.04 sqrt(2/pi) = 3.2 points (a little less: clipped to [0, 1])
    assert noisy["mae"]["value"] == pytest.approx(100 * 0.04 * (2 / 3.14159) ** 0.5, rel=0.1)
    assert noisy["mae"]["low"] < noisy["mae"]["value"] < noisy["mae"]["high"]
    # the close pairs (0.5, 0.52) and (0.6, 0.61) swap often; the far ones almost never
    assert 0.0 < noisy["mmrv"]["value"] < 10.0
    wider = noise_floor([dict(c, real_sd=0.08) for c in cells], draws=2000)
    assert wider["mmrv"]["value"] > noisy["mmrv"]["value"]
    assert noise_floor(spread, draws=50, seed=3) == noise_floor(spread, draws=50, seed=3)


def test_a_smoke_run_writes_every_part_of_the_page(tmp_path):
    real = {
        name: Dataset(tuple(_frames(people=9, n_frames=30, seed=s)), name=name)
        for name, s in (("one", 1), ("two", 2))
    }
    result = run_twins(
        real, root=tmp_path / "twins", detectors=("proximity", "majority"),
        tuned=("proximity",), episodes=2, jobs=1,
    )  # fmt: skip
    assert result.datasets == ("one", "two")
    assert {c["detector"] for c in result.cells} == {"proximity", "majority"}
    assert all(c["real_sd"] >= 0.0 for c in result.cells)
    # two voters (the majority baseline has no vote) are too few to calibrate: no agreements
    assert not any("agreement_place" in c or "agreement_twin" in c for c in result.cells)
    assert set(result.noise_floor) == {"mae", "mmrv"}
    assert {r["how"] for r in result.tuning} == {"one setting", "twin", "labels"}
    assert (tmp_path / "twins" / "one" / "twin.json").is_file()
    page = to_markdown(result, command="reform-sim experiment twins --out x", figure="t.png")
    for heading in ("## Tuning", "## Prediction", "## Leave one out", "Goals met", "a floor"):
        assert heading in page
    _assert_whole_tables(page)
    assert scatter_figure(result, tmp_path / "t.png").read_bytes()[:4] == b"\x89PNG"

    # the same run with another seed (here: every prediction 0.1 higher), and the two together
    cells = tuple(dict(c, predicted=min(1.0, c["predicted"] + 0.1)) for c in result.cells)
    other = dataclasses.replace(
        result, seed=1, cells=cells, agreement={"twin": agreement(cells, "predicted")}
    )
    seeds = across_seeds([result, other])
    assert seeds["seeds"] == [0, 1]
    mae = [goal_figures(r)["mae"] for r in (result, other)]
    assert seeds["spread"]["mae"] == {"mean": np.mean(mae), "low": min(mae), "high": max(mae)}
    middle = [dict(c, predicted=(c["predicted"] + d["predicted"]) / 2) for c, d in
              zip(result.cells, cells, strict=True)]  # fmt: skip
    assert seeds["mean_prediction"]["mae"] == agreement(middle, "predicted")["mae"]["value"]
    assert [c["predicted"] for c in seeds["cells"]["1"]] == [c["predicted"] for c in cells]
    # a detector trained on each run's twin is another model in each: the real F1s averaged
    retrained = tuple(dict(c, real=c["real"] / 2) for c in cells)
    pair = across_seeds([result, dataclasses.replace(other, cells=retrained)])
    both = [dict(m, real=(c["real"] + d["real"]) / 2) for m, c, d in
            zip(middle, result.cells, retrained, strict=True)]  # fmt: skip
    assert pair["mean_prediction"]["mae"] == agreement(both, "predicted")["mae"]["value"]
    page = to_markdown(dataclasses.replace(result, seeds=seeds), command="x")
    assert "## Seeds" in page and "mean over 2 seeds (lowest to highest)" in page

    # two twins a place, twice: each place predicted by the mean of its two twins' predictions
    runs = [result, other, dataclasses.replace(result, seed=2), dataclasses.replace(other, seed=3)]
    pairs = across_seeds(runs, per_place=2)
    assert [e["seeds"] for e in pairs["ensembles"]] == [[0, 1], [2, 3]]
    assert pairs["ensembles"][0]["mae"] == agreement(middle, "predicted")["mae"]["value"]
    gain = [goal_figures(r)["tuning_gain"] for r in (result, other)]
    assert pairs["ensembles"][1]["tuning_gain"] == pytest.approx(np.mean(gain), nan_ok=True)
    assert pairs["spread"]["mae"]["mean"] == pytest.approx(pairs["ensembles"][0]["mae"])
    assert pairs["single"]["mae"] == {"mean": np.mean(mae), "low": min(mae), "high": max(mae)}
    page = to_markdown(dataclasses.replace(result, seeds=pairs), command="x")
    assert "mean over 2 repeats, 2 twins a place (lowest to highest)" in page
    assert "| 0, 1 |" in page and "| 2, 3 |" in page
    assert "The goals are judged on 2 twins a place" in page
    places = place_errors(pairs)  # each dataset's error under each pair's mean prediction
    assert set(places) == {"one", "two"} and len(places["one"]["mae"]) == 2
    ones = [c for c in middle if c["dataset"] == "one"]
    assert places["one"]["mae"][0] == agreement(ones, "predicted")["mae"]["value"]
    assert "Each place's prediction by 2 twins" in page and "| one |" in page
    _assert_whole_tables(page)
    with pytest.raises(ValueError, match="per_place: expected a divisor of the 3 runs, found 2"):
        across_seeds(runs[:3], per_place=2)


def _assert_whole_tables(page: str) -> None:
    """Each Markdown table of ``page`` stands apart: a head, its rule and rows, no blank line
    between its rows and no text run into it."""
    for block in page.split("\n\n"):
        lines = block.strip().splitlines()
        rows = [k for k, line in enumerate(lines) if line.startswith("|")]
        if rows:
            assert rows == list(range(len(lines))), block  # no text in a table's block
            assert len(lines) > 2 and lines[1].startswith(("|:", "|-")), block  # head, rows


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--repeats", "0"], "--repeats: expected 1 to 20, found 0"),
        (["--repeats", "21"], "--repeats: expected 1 to 20, found 21"),
        (["--twins-per-place", "0"], "--twins-per-place: expected 1 to 10 with --repeats 3 (at "
         "most 30 seeds), found 0"),  # fmt: skip
        (["--repeats", "4", "--twins-per-place", "8"], "--twins-per-place: expected 1 to 7 with "
         "--repeats 4 (at most 30 seeds), found 8"),  # fmt: skip
    ],
)
def test_repeats_out_of_range_are_refused_in_one_line(extra, message, tmp_path, capsys):
    from sim.cli import main

    argv = ["experiment", "twins", "--out", str(tmp_path / "out"), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"reform-sim experiment: error: {message}"]
    assert not (tmp_path / "out").exists()


def test_a_dataset_too_small_for_a_twin_is_refused_before_any_twin_is_fitted(tmp_path, capsys):
    from reform.datasets import write_parquet
    from tests.cli_errors import cli_error

    good, nine = tmp_path / "good.parquet", tmp_path / "nine.parquet"
    write_parquet(Dataset(tuple(_frames(n_frames=30)), name="good"), good)
    write_parquet(Dataset(tuple(_frames(n_frames=9)), name="nine"), nine)
    out = tmp_path / "out"
    argv = ["experiment", "twins", "--out", out, "--data", good, "--data", nine,
            "--repeats", 1, "--twins-per-place", 1]  # fmt: skip
    line = cli_error(argv, capsys)
    assert line == (
        f"reform-sim experiment: error: --data {nine}: field frames: expected at least 10 "
        "frames to fit a twin, found 9"
    )
    assert not out.exists()


def test_a_dataset_given_twice_is_refused_naming_it(tmp_path, capsys):
    from tests.cli_errors import cli_error

    out = tmp_path / "out"
    line = cli_error(["experiment", "twins", "--out", out, "--data", "salsa", "--data", "salsa"],
                     capsys)  # fmt: skip
    assert line == (
        "reform-sim experiment: error: --data salsa: dataset salsa is given twice (also as "
        "--data salsa); give each dataset once"
    )
    assert not out.exists()


def test_one_recording_under_two_names_is_refused_naming_both(tmp_path, shared_datasets, capsys):
    from tests.cli_errors import cli_error

    out = tmp_path / "out"
    salsa = shared_datasets / "salsa"
    line = cli_error(
        ["experiment", "twins", "--out", out, "--data", f"party={salsa}",
         "--data", f"again={salsa}/"],
        capsys,
    )  # fmt: skip
    assert line == (
        f"reform-sim experiment: error: --data again={salsa}/: dataset {salsa.resolve()} is "
        f"given twice (also as --data party={salsa}); give each dataset once"
    )
    assert not out.exists()

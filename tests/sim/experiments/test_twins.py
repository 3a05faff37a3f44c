"""The venue-twins experiment: its measures pinned by hand, and a smoke run end to end."""

from __future__ import annotations

import pytest

from reform.frame import Dataset
from sim.experiments.twins import agreement, mmrv, run_twins
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
    assert {r["how"] for r in result.tuning} == {"one setting", "twin", "labels"}
    assert (tmp_path / "twins" / "one" / "twin.json").is_file()
    page = to_markdown(result, command="reform-sim experiment twins --out x", figure="t.png")
    for heading in ("## Tuning", "## Prediction", "## Leave one out", "Goals met"):
        assert heading in page
    for table in page.split("\n\n"):  # no table broken by a blank line between its rows
        lines = table.strip().splitlines()
        if lines and lines[0].startswith("|"):
            assert len(lines) > 2 and lines[1].startswith(("|:", "|-")), table  # head, rows
    assert scatter_figure(result, tmp_path / "t.png").read_bytes()[:4] == b"\x89PNG"

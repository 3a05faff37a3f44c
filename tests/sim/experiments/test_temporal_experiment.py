"""``reform-sim experiment temporal``: the default party and the real datasets scored per frame
and in time, and the temporal filters' goal checked on the party (smoke sizes)."""

from __future__ import annotations

import json

import pytest
from cli_errors import cli_error

from sim.cli import main
from sim.experiments.temporal import (
    MAX_ADDED_LATENCY_S,
    MAX_FLICKER_RATIO,
    PARTIES,
    SCRIPTED,
    party_frames,
)


def test_the_party_is_the_same_for_the_same_seed():
    one = party_frames(seed=3, episodes=2, duration=10.0, rate=2.0)
    again = party_frames(seed=3, episodes=2, duration=10.0, rate=2.0)
    other = party_frames(seed=4, episodes=2, duration=10.0, rate=2.0)
    assert one.frames == again.frames and one.frames != other.frames
    scripted = party_frames(seed=3, episodes=2, duration=10.0, rate=2.0, options=PARTIES[SCRIPTED])
    assert scripted.frames != one.frames  # the same seeds, changes scripted in
    assert [f.sequence for f in one.frames[::20]] == ["party-0", "party-1"]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("temporal")
    argv = ["experiment", "temporal", "--data", "none", "--episodes", "2", "--duration", "40"]
    argv += ["--rate", "2", "--detector", "gcff", "--detector", "smoothed", "--out", str(out)]
    assert main([*argv, "-q"]) == 0
    return out


def test_the_report_holds_every_cell_in_time_and_the_filters_goal(report):
    document = json.loads((report / "temporal.json").read_text())
    assert document["party"]["frames"] == 2 * 40 * 2
    datasets = {c["dataset"] for c in document["benchmark"]["cells"]}
    assert datasets == {"party (simulated)", "party with scripted changes (simulated)"}
    cells = {
        c["detector"]: c
        for c in document["benchmark"]["cells"]
        if c["dataset"] == "party (simulated)"
    }
    assert set(cells) == {"GCFF, one setting (0.7 m, 30,000 cm²)", "smoothed"}
    base, filtered = cells["GCFF, one setting (0.7 m, 30,000 cm²)"], cells["smoothed"]
    (goal,) = document["goals"]
    assert (goal["filter"], goal["detector"]) == ("smoothed", "gcff")
    flicker = [c["temporal"]["false_events_per_minute"] for c in (base, filtered)]
    latency = [c["temporal"]["latency_s"]["median"] for c in (base, filtered)]
    f1 = [c["scores"]["T=2/3"]["f1"] for c in (base, filtered)]
    assert goal["false_events_per_minute"] == flicker and goal["f1_2/3"] == f1
    expected = (
        flicker[1] <= MAX_FLICKER_RATIO * flicker[0]
        and None not in latency
        and latency[1] - latency[0] <= MAX_ADDED_LATENCY_S + 1e-9
        and f1[1] >= f1[0]
    )
    assert goal["met"] == expected
    page = (report / "temporal.md").read_text()
    assert "## The filters on the default party" in page and "## party (simulated)" in page
    assert "## party with scripted changes (simulated)" in page
    assert (report / "temporal.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--episodes", "0"], "--episodes must be at least 1, got 0"),
        (["--data", "none", "--data", "salsa"], "--data none runs the party alone"),
        (["--detector", "nonesuch"], "--detector nonesuch: "),
    ],
)
def test_bad_arguments_are_one_line(extra, message, tmp_path, capsys):
    err = cli_error(["experiment", "temporal", *extra, "--out", tmp_path], capsys)
    assert err.startswith("reform-sim experiment: error: " + message), err
    assert not (tmp_path / "temporal.md").exists()

"""Stress tests (sim.experiments.stress and stress_report, reform-sim stress) on a tiny grid."""

from __future__ import annotations

import dataclasses
import json
import re

import matplotlib.image
import pytest

from reform.seeding import Role, derive_int
from sim.cli import main
from sim.experiments.stress import (
    AXES,
    DETECTORS,
    GRIDS,
    StressGrid,
    run_stress,
    train_detectors,
    training_frames,
)
from sim.experiments.stress_report import recording_names, write_report

# Two levels per axis (the small grid's ends), short episodes: every code path, a few seconds.
SMALL = GRIDS["small"]
TINY = dataclasses.replace(
    SMALL,
    **{
        axis: (getattr(SMALL, axis)[0], getattr(SMALL, axis)[-1])
        for axis in ("position_noise_m", "orientation_noise_deg", "dropout")
    },
    people=(8, 24),
    crowd_people=(50, 100),
    duration_s=30.0,
    train_duration_s=60.0,
    resamples=100,
)


@pytest.fixture(scope="module")
def detectors():
    frames = training_frames(seed=0, episodes=1, duration=60.0, rate=0.5, jobs=1)
    return train_detectors(frames, grid=TINY, jobs=1)


@pytest.fixture(scope="module")
def results(detectors):
    return run_stress(TINY, seed=0, jobs=1, detectors=detectors)


def test_every_axis_and_detector_is_scored(results) -> None:
    assert [a.name for a in results.axes] == list(AXES)
    for axis in results.axes:
        assert len(axis.points) == 2
        for point in axis.points:
            assert point.episodes == 2 and point.frames > 0
            assert set(point.scores) == set(DETECTORS)
            for by_threshold in point.scores.values():
                for s in by_threshold.values():
                    assert 0.0 <= s.f1.low <= s.f1.high <= 1.0
                    assert 0.0 <= s.f1.value <= 1.0


def test_unperturbed_levels_agree(results) -> None:
    # Level 0 of the three perturbation axes is the same unperturbed frames.
    first = [results.axis(a).points[0] for a in ("position-noise", "orientation-noise", "dropout")]
    for detector in DETECTORS:
        values = {p.scores[detector]["2/3"].f1.value for p in first}
        assert len(values) == 1


def test_half_a_metre_of_noise_hurts_every_detector(results) -> None:
    axis = results.axis("position-noise")
    for detector in DETECTORS:
        clean, noisy = axis.curve(detector, "2/3")[0]
        assert noisy < clean - 0.05


def test_scene_axes_change_the_scene(results) -> None:
    groups = results.axis("groups").points
    assert groups[1].fformations_per_frame > groups[0].fformations_per_frame
    assert groups[1].people_per_frame == 24 and groups[0].people_per_frame == 8
    sensor = results.axis("sensor").points
    assert [p.label for p in sensor] == ["truth", "occlusion"]
    assert sensor[1].people_per_frame < sensor[0].people_per_frame  # the robot sees fewer
    for point in results.axis("density").points:
        assert point.people_per_m2 == pytest.approx(point.value, rel=0.01)
    dropout = results.axis("dropout").points
    assert dropout[1].people_per_frame < dropout[0].people_per_frame
    # A larger concourse: more people in each frame (walkers come and go) and more groups.
    small, large = results.axis("crowd").points
    assert 30 < small.people_per_frame <= 50 < large.people_per_frame <= 100
    assert large.fformations_per_frame > small.fformations_per_frame


def test_the_event_rate_axis_scripts_changes_into_the_same_parties(results) -> None:
    # No scripted change: the party of every other scene axis at its defaults (largest group
    # 8, mingle's default), the same episodes scored the same.
    assert SMALL.event_rate_per_min == (0.0, 8.0) and SMALL.max_group_size[-1] == 8
    still, busy = results.axis("event-rate").points
    base = results.axis("group-size").points[-1]
    assert (still.frames, still.fformations_per_frame) == (base.frames, base.fformations_per_frame)
    for detector in DETECTORS:
        assert still.scores[detector]["2/3"].f1.value == base.scores[detector]["2/3"].f1.value
    # Eight changes a minute: people walk up, drift away and merge, so the groups differ.
    assert busy.frames == still.frames and busy.people_per_frame == still.people_per_frame
    assert busy.fformations_per_frame != still.fformations_per_frame


def test_a_crowd_axis_past_the_machine_is_refused_before_any_work(tmp_path, capsys) -> None:
    """The default grid's crowd axis (up to 1,000 people) in 1 GiB with two workers: refused
    in one line naming the crowd asked, the largest that fits and what to change; nothing is
    written."""
    out = tmp_path / "report"
    code = main(
        ["stress", "--axes", "crowd", "--jobs", "2", "--max-memory", "1G", "--out", str(out)]
    )
    assert code == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    found = re.search(
        r"the crowd axis of --grid default asks for a concourse of 1,000 people, more than "
        r"--max-memory 1 GiB holds with 2 workers: at most (\d+) people fit; leave crowd out "
        r"of --axes, run the small --grid, give fewer --jobs or a larger --max-memory$",
        line,
    )
    assert found and 50 <= int(found[1]) < 1000, line
    assert not out.exists()
    with pytest.raises(
        ValueError, match=r"StressGrid.crowd_people values must lie in \[50, 3000\], got 5000"
    ):
        StressGrid(crowd_people=(100, 5000))


def test_training_and_test_seeds_differ() -> None:
    train = {derive_int(0, Role.STRESS_TRAIN, s, i) for s in range(2) for i in range(4)}
    test = {derive_int(0, Role.STRESS_TEST, i) for i in range(5)}
    assert len(train) == 8 and len(test) == 5 and not train & test


def test_results_do_not_depend_on_the_number_of_workers(detectors, results) -> None:
    two = run_stress(TINY, seed=0, jobs=2, detectors=detectors, axes=["dropout"])
    for a, b in zip(two.axis("dropout").points, results.axis("dropout").points, strict=True):
        assert a.to_json() == b.to_json()


def test_report_files(results, tmp_path) -> None:
    from rerun.chunk import RrdReader

    written = write_report(results, tmp_path, command="reform-sim stress", save=tmp_path / "s.rrd")
    markdown = written["markdown"].read_text()
    assert "reform-sim stress" in markdown
    for axis in results.axes:
        assert f"## {axis.title}" in markdown
        image = matplotlib.image.imread(written[f"plot:{axis.name}"])
        assert image.ndim == 3 and image.shape[0] > 100
    data = json.loads(written["json"].read_text())
    assert data["kind"] == "reform-sim/stress"
    point = data["axes"][0]["points"][1]
    expected = results.axes[0].points[1].scores["bagged-trees"]["1"].f1.value
    assert point["scores"]["bagged-trees"]["1"]["f1"]["value"] == pytest.approx(expected)
    store = RrdReader(written["recording"]).stream().collect()
    paths = {chunk.entity_path for chunk in store.stream()}
    for name in recording_names(results):
        assert f"/dataset/stress/{name}/table" in paths
        assert f"/dataset/stress/{name}/GCFF" in paths


class Alone:
    """A plugin detector: everyone alone (F1 0 wherever there is a true F-formation)."""

    def predict(self, frames):
        return [tuple((int(i),) for i in frame.ids) for frame in frames]


def test_a_plugin_is_reported_plotted_and_recorded_beside_the_built_ins(detectors, tmp_path):
    from rerun.chunk import RrdReader

    name = "myplugin:make"  # as `reform-sim stress --detector myplugin:make` names it
    results = run_stress(
        TINY, seed=0, jobs=1, detectors=detectors, plugins={name: Alone()}, axes=["dropout"]
    )
    assert list(results.detectors)[-1] == name
    written = write_report(results, tmp_path, command="c", save=tmp_path / "s.rrd")
    markdown = written["markdown"].read_text()
    builtins = ["REFORM weighted KNN", "REFORM bagged trees", "REFORM logistic regression", "GCFF"]
    headers = [
        [cell.strip() for cell in line.strip("|").split("|")]
        for line in markdown.splitlines()
        if line.startswith(("| axis ", "| level "))
    ]
    # The summary, then per threshold the axis's F1 table (the first "level" table is context).
    assert headers[0] == ["axis", "from → to", *builtins, name]
    assert headers[2:] == [["level", *builtins, name]] * 2
    clean = results.axis("dropout").points[0].scores[name]["2/3"].f1.value
    assert clean == 0.0  # the test parties hold groups; everyone alone finds none
    image = matplotlib.image.imread(written["plot:dropout"])
    assert image.ndim == 3 and image.shape[0] > 100
    paths = {str(chunk.entity_path) for chunk in RrdReader(written["recording"]).stream()}
    for curves in recording_names(results):
        root = f"/dataset/stress/{curves}/"
        assert {f"{root}GCFF", f"{root}REFORM_bagged_trees"} <= paths
        # Rerun escapes the ':' of a module:factory name in entity paths.
        assert {p for p in paths if p.startswith(root) and "myplugin" in p} == {
            f"{root}myplugin\\:make"
        }


def test_reading_notes_follow_the_axes_that_ran(results, tmp_path) -> None:
    every = write_report(results, tmp_path / "all", command="c")["markdown"].read_text()
    for word in ("**Dropout**", "**Sensor**", "**Density**", "**Number of groups**", "Scene axes"):
        assert word in every
    noise = [a for a in results.axes if a.name == "position-noise"]
    only = write_report(
        dataclasses.replace(results, axes=tuple(noise)), tmp_path / "n", command="c"
    )
    text = only["markdown"].read_text()
    assert "## Position noise" in text and "Reading the curves" not in text
    dropout = [a for a in results.axes if a.name in ("position-noise", "dropout")]
    two = write_report(
        dataclasses.replace(results, axes=tuple(dropout)), tmp_path / "t", command="c"
    )
    text = two["markdown"].read_text()
    assert "**Dropout**" in text
    assert "**Density**" not in text and "**Sensor**" not in text and "Scene axes" not in text


def test_grid_validation() -> None:
    with pytest.raises(ValueError, match=r"StressGrid.dropout values must lie in \[0, 1\], got 2"):
        StressGrid(dropout=(0.0, 2.0))
    with pytest.raises(ValueError, match="StressGrid.sensors must be names of"):
        StressGrid(sensors=("lidar",))
    with pytest.raises(ValueError, match="StressGrid.people must hold at least one level"):
        StressGrid(people=())
    with pytest.raises(
        ValueError, match=r"StressGrid.event_rate_per_min values must lie in \[0, 20\], got 30"
    ):
        StressGrid(event_rate_per_min=(0.0, 30.0))
    with pytest.raises(ValueError, match="grid must be one of"):
        run_stress("huge")
    with pytest.raises(ValueError, match="axis must be one of"):
        run_stress(TINY, axes=["weather"])


def test_cli_runs_one_axis(tmp_path, capsys) -> None:
    out = tmp_path / "report"
    code = main(
        ["stress", "--grid", "small", "--axes", "dropout", "--episodes", "1", "--jobs", "1"]
        + ["--out", str(out)]
    )
    assert code == 0
    markdown = (out / "stress.md").read_text()
    assert "reform-sim stress --grid small --episodes 1 --axes dropout --jobs 1 --out" in markdown
    assert (out / "stress-dropout.png").is_file()
    captured = capsys.readouterr()
    assert f"wrote markdown: {out / 'stress.md'}" in captured.out
    # Its estimate, stated once before the work.
    assert captured.err.count("the stress test: about ") == 1
    assert "(estimates, sim.sizing)" in captured.err.splitlines()[0]


def test_the_whole_catalogue_runs_beside_the_built_ins(detectors) -> None:
    """What ``stress --detector all`` adds: every catalogued detector that needs no model file
    and no dataset of its own, each scored at every point (the one that learns fitted on the
    training frames)."""
    from reform.detectors import builtin_names, make_detector

    names = [n for n in builtin_names(needs=("", "training")) if n not in DETECTORS]
    assert "gcff" in names and "majority" in names and "gcff-tuned" not in names
    plugins = {name: make_detector(name) for name in names}
    results = run_stress(
        TINY, seed=0, jobs=1, detectors=detectors, plugins=plugins, axes=["dropout"]
    )
    for point in results.axis("dropout").points:
        for name in names:
            assert 0.0 <= point.scores[name]["2/3"].f1.value <= 1.0, name
    clean = results.axis("dropout").points[0].scores
    assert clean["majority"]["2/3"].f1.value == 0.0
    assert clean["gcff"]["2/3"].f1.value > 0.5  # the test parties' groups are there to find


def test_temporal_scores_every_point_in_time_and_leaves_the_frame_scores_alone(
    detectors, results, tmp_path
) -> None:
    from reform import Majority

    timed = run_stress(
        TINY,
        seed=0,
        jobs=1,
        detectors=detectors,
        axes=["event-rate"],
        plugins={"majority": Majority()},
        temporal=True,
    )
    for point, plain in zip(
        timed.axis("event-rate").points, results.axis("event-rate").points, strict=True
    ):
        assert point.scores == {d: plain.scores[d] for d in plain.scores} | {
            "majority": point.scores["majority"]
        }
        assert set(point.temporal) == {*DETECTORS, "majority"}
        for scores in point.temporal.values():
            assert scores["true_events"] > 0 and scores["tolerance_s"] == 2.0  # 0.5 Hz frames
        # everyone alone: no event detected, none invented, none found
        majority = point.temporal["majority"]
        assert (majority["detected_events"], majority["false_events_per_minute"]) == (0, 0.0)
        assert majority["recall"] == 0.0 and majority["precision"] is None
        assert "temporal" in point.to_json() and "temporal" not in plain.to_json()
    write_report(timed, tmp_path, command="reform-sim stress --temporal")
    page = (tmp_path / "stress.md").read_text()
    assert "## Groups in time (false events per minute / event recall %" in page

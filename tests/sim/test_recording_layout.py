"""The default layout of recordings: every panel shows data, every plot holds its values.

Read back from real .rrd files: the blueprint store (views, contents, axis ranges) against the
recording store (entities, scalars). The "F-formations per frame" plot once opened on an empty
-1 to 1 axis: it had no y range, and the viewer's own range, found from what it has drawn,
falls back to -1..1 when nothing is drawn yet or every value is the same (a constant count
of 0); and runs without counts (a stress test) still showed the panel.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import rerun as rr
from recorded_layout import RecordedData, assert_every_panel_holds_data, panels

import scenarios
from reform.detectors import make_detector, run_detector
from sim.episode import simulate_episode
from sim.recording import (
    default_blueprint,
    log_stress_curves,
    open_recording,
    record_episode,
    record_evaluation,
)


@pytest.fixture(scope="module")
def word_improv(tmp_path_factory) -> dict:
    """20 s of the Babble game: one circle all along (a constant count of 1 F-formation)."""
    episode = simulate_episode(scenarios.make("word-improv", seed=0), duration=20.0)
    frames = episode.truth
    detections = {
        "gcff": run_detector("gcff", make_detector("gcff"), frames),
        "majority": run_detector("majority", make_detector("majority"), frames),
    }
    path = tmp_path_factory.mktemp("layout") / "word-improv.rrd"
    record_episode(
        path, frames, detections=detections, events=episode.events, model=episode.model, seed=0
    )
    return {"path": path, "frames": frames, "detections": detections}


def test_every_panel_of_an_episode_shows_data_in_range(word_improv) -> None:
    shown = assert_every_panel_holds_data(word_improv["path"])
    by_name = {p.name: p for p in shown}
    counts = by_name["F-formations per frame (count)"]
    assert counts.origin == "/metrics/groups"
    data = RecordedData(word_improv["path"])
    # Constant counts, where the viewer's own range falls back to -1..1: the truth's is 1 in
    # every frame, majority's 0 (it leaves everyone alone, the majority class of pairs).
    assert set(data.scalars["/metrics/groups/truth"]) == {1.0}
    assert set(data.scalars["/metrics/groups/majority"]) == {0.0}
    most = max(max(v) for k, v in data.scalars.items() if k.startswith("/metrics/groups/"))
    assert counts.y_range == (-0.5, most + 0.5)
    assert {p.kind for p in shown} == {"3D", "TimeSeries", "TextLog"}
    assert by_name["Running F1 (T = 2/3), per frame"].y_range == (0.0, 1.0)


def test_a_run_without_truth_or_detectors_shows_only_its_scene(tmp_path: Path, word_improv) -> None:
    frames = [f.replace(groups=None) for f in word_improv["frames"]]
    path = tmp_path / "plain.rrd"
    record_episode(path, frames, seed=0)
    shown = assert_every_panel_holds_data(path)
    assert [p.kind for p in shown] == ["3D"]


def test_an_evaluation_with_dataset_views_shows_data_in_every_panel(
    tmp_path: Path, word_improv
) -> None:
    path = tmp_path / "evaluation.rrd"
    frames = word_improv["frames"]
    record_evaluation(path, frames, {"gcff": word_improv["detections"]["gcff"]}, name="eval")
    shown = assert_every_panel_holds_data(path)
    # The groups hold for these 20 s, in the truth and for GCFF: no group event, no event log.
    assert {"BarChart", "TextDocument", "2D", "3D", "TimeSeries"} == {p.kind for p in shown}


def test_a_stress_recording_has_no_empty_run_panels(tmp_path: Path) -> None:
    path = tmp_path / "stress.rrd"
    blueprint = default_blueprint(scene=False, scores=False, events=False, stress=["noise"])
    with open_recording(path, name="stress", blueprint=blueprint) as rec:
        log_stress_curves(
            rec, [0.0, 0.1], {"reform F1": [0.9, 0.8]}, x_label="noise (m)", name="noise"
        )
    shown = assert_every_panel_holds_data(path)
    assert [p.kind for p in shown] == ["BarChart", "TextDocument"]


def test_the_old_layout_fails_the_check(tmp_path: Path) -> None:
    """The check can fail: a counts panel with no range, and a run tab with nothing in it."""
    path = tmp_path / "old.rrd"
    with open_recording(path, name="old", blueprint=default_blueprint(max_groups=None)) as rec:
        rec.log("world/room", rr.Points3D([[0.0, 0.0, 0.0]]), static=True)
    with pytest.raises(AssertionError, match="shows no data"):
        assert_every_panel_holds_data(path)
    assert [p.name for p in panels(path)][-1] == "Events"
    with pytest.raises(ValueError, match="max_groups must be None or an int >= 0, got -1"):
        default_blueprint(max_groups=-1)
    with pytest.raises(ValueError, match="needs the scene or a dataset view"):
        default_blueprint(scene=False)

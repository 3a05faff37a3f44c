"""The paper's HRI proof of concept re-enacted (sim.experiments.hri, reform-sim experiment hri)."""

from __future__ import annotations

import json

import pytest

from reform import Reform, time_split
from reform.classifiers import make_classifier
from reform.detectors import DetectorError
from sim.experiments.hri import (
    HRI_SCENARIOS,
    PAPER_HRI,
    VIEWS,
    HriDetector,
    hri_detectors,
    hri_episodes,
    hri_experiment,
    record_scenes,
)
from sim.experiments.hri_report import to_markdown

SEEDS = 2


@pytest.fixture(scope="module")
def detectors(salsa_dataset):
    """SALSA-trained REFORM (logistic regression, on part of the training split) and the
    experiment's synthetic-trained models, GCFF and majority on the small grid."""
    train, _ = time_split(salsa_dataset.annotated())
    salsa = HriDetector(
        "logistic-regression@salsa",
        "REFORM logistic regression, SALSA-trained",
        "SALSA train",
        Reform(make_classifier("logistic-regression")).fit(train[::4]),
    )
    others, training = hri_detectors(salsa=None, seed=0, grid="small", jobs=1)
    return [salsa, *others], training


@pytest.fixture(scope="module")
def experiment(detectors):
    fitted, training = detectors
    return hri_experiment(
        seed=0, seeds=SEEDS, detectors=fitted, training=training, resamples=100, rate=1.0
    )


def test_rows_cover_every_detector_view_and_scene(experiment, detectors) -> None:
    keys = [d.key for d in detectors[0]]
    assert experiment.detectors == tuple(keys)
    assert "logistic-regression@salsa" in keys and "bagged-trees@synthetic" in keys
    for key in keys:
        for view in VIEWS:
            for scenario in (*HRI_SCENARIOS, "all"):
                row = experiment.row(key, view, scenario)
                assert set(row.scores) == {"2/3", "1"}


def test_passing_frames_are_degenerate(experiment) -> None:
    # No true F-formation: recall 1 whatever is detected; precision 1 only when nothing is.
    for key in experiment.detectors:
        for view in VIEWS:
            row = experiment.row(key, view, "hri-passing")
            assert row.scores["2/3"].recall.value == 1.0
            assert row.scores["1"].recall.value == 1.0
            precision, recall, _ = row.micro["2/3"]
            assert recall == 1.0 and precision in (0.0, 1.0)
    majority = experiment.row("majority", "truth", "hri-passing").scores["2/3"]
    assert majority.f1.value == 1.0
    assert experiment.row("majority", "truth", "hri-conversation").scores["2/3"].recall.value < 0.5


def test_the_scenes_hold_what_the_paper_describes(experiment) -> None:
    truth = experiment.data["truth"]
    assert truth["hri-passing"]["frames_with_fformation"] == 0.0
    assert truth["hri-conversation"]["frames_with_fformation"] > 0.5
    assert truth["hri-conversation"]["people_per_frame"] == pytest.approx(3.0, abs=0.1)
    for scenario in HRI_SCENARIOS:
        assert (
            experiment.data["robot"][scenario]["people_per_frame"]
            < truth[scenario]["people_per_frame"]
        )
        assert experiment.data["robot"][scenario]["episodes"] == SEEDS


def test_reform_finds_the_conversations_from_the_ground_truth(experiment) -> None:
    for key in ("logistic-regression@salsa", "logistic-regression@synthetic"):
        for scenario in ("hri-conversation", "hri-robot-excluded"):
            assert experiment.row(key, "truth", scenario).scores["2/3"].recall.value > 0.8


def test_report(experiment) -> None:
    markdown = to_markdown(experiment, command="reform-sim experiment hri --out hri")
    assert "reform-sim experiment hri --out hri" in markdown
    for name, (_, _, f1) in PAPER_HRI.items():
        assert f"paper: {name}" in markdown and f"{f1:.1f}" in markdown
    assert "Degenerate frames" in markdown and "SALSA-trained" in markdown
    data = json.loads(json.dumps(experiment.to_json(command="x"), allow_nan=False))
    assert data["kind"] == "reform-sim/hri-experiment"
    assert len(data["rows"]) == len(experiment.rows)


@pytest.mark.slow
def test_ray_backend_gives_the_local_experiment(detectors, experiment, ray_instance) -> None:
    """Training and episodes as Ray tasks on a real local instance: the same report."""
    from sim.executor import Executor

    fitted, training = detectors
    with Executor("ray") as executor:
        others, remote_training = hri_detectors(salsa=None, seed=0, grid="small", executor=executor)
        remote = hri_experiment(
            seed=0,
            seeds=SEEDS,
            detectors=[fitted[0], *others],
            training=remote_training,
            resamples=100,
            rate=1.0,
            executor=executor,
        )
    assert remote_training == training
    ours, theirs = experiment.to_json(command="x"), remote.to_json(command="x")
    del ours["timings_s"], theirs["timings_s"]
    assert len(ours["rows"]) > 0
    assert theirs == ours


def test_episodes_are_deterministic() -> None:
    a = hri_episodes(seed=3, seeds=1, rate=1.0, views=("truth",))
    b = hri_episodes(seed=3, seeds=1, rate=1.0, views=("truth",))
    assert a.keys() == b.keys()
    for key in a:
        assert a[key] == b[key]


def test_recordings(detectors, tmp_path) -> None:
    from rerun.chunk import RrdReader

    paths = record_scenes(detectors[0], tmp_path, seed=0, rate=1.0)
    assert [p.name for p in paths] == [f"{s}.rrd" for s in HRI_SCENARIOS]
    store = RrdReader(paths[0]).stream().collect()
    entities = {chunk.entity_path for chunk in store.stream()}
    assert any(path.startswith("/world") for path in entities)
    assert any("reform" in path for path in entities) and any("gcff" in path for path in entities)


class Forgets:
    """A broken detector: puts each frame's first agent in a group and forgets the others."""

    def predict(self, frames):
        return [((int(frame.ids[0]),),) for frame in frames]


def test_a_broken_detector_is_one_line_naming_it_the_view_and_the_frame() -> None:
    broken = HriDetector("forgets", "Forgets everyone", "-", Forgets())
    # One line (no '.' matches a newline): the detector's label and view, then the frame.
    with pytest.raises(
        DetectorError,
        match=r"^Forgets everyone \(truth view\): detector output for frame 0 "
        r"\(hri-conversation-\d+ t=\d+ s\): person \d+ is in no group; a prediction must be a "
        r"full partition of the frame's ids, singletons included$",
    ):
        hri_experiment(
            seed=0, seeds=1, views=("truth",), detectors=[broken], resamples=10, rate=1.0
        )


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="views must be among"):
        hri_episodes(seed=0, seeds=1, views=("sonar",))
    with pytest.raises(ValueError, match="seeds must be an int >= 1, got 0"):
        hri_experiment(seeds=0, detectors=[])
    with pytest.raises(ValueError, match="grid must be one of"):
        hri_detectors(salsa=None, seed=0, grid="huge")

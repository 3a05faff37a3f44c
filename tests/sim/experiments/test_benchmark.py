"""``reform-sim benchmark``: every detector on every dataset, scored as the field reports it."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
import zlib
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from reform.detectors import DetectorError
from sim.cli import main
from sim.experiments.benchmark import (
    DatasetSpec,
    detector_spec,
    one_recording_each,
    run_benchmark,
)


def _cell(items) -> np.ndarray:
    array = np.empty((1, len(items)), dtype=object)
    for k, item in enumerate(items):
        array[0, k] = item
    return array


def _gcff(folder: Path, frames, *, settings=None) -> Path:
    """A GCFF folder (centimetres) from ``[(people rows, groups), ...]``, every frame annotated."""
    folder.mkdir(parents=True, exist_ok=True)
    stamps = np.arange(1, len(frames) + 1, dtype=np.float64)[None, :]
    features = _cell([np.asarray(people, dtype=np.float64) for people, _ in frames])
    scipy.io.savemat(folder / "features.mat", {"features": features, "timestamp": stamps})
    gt = _cell([_cell([np.array([g], dtype=np.float64) for g in groups]) for _, groups in frames])
    scipy.io.savemat(folder / "groundtruth.mat", {"GTgroups": gt, "GTtimestamp": stamps})
    if settings is not None:
        scipy.io.savemat(folder / "settings_gc.mat", settings)
    return folder


# Two people 1 m apart facing each other, a third far away facing off: GCFF (stride 0.5 m)
# finds the pair; the ground truth lists the pair, and once a member (42) the tracker lost.
PAIR = [[1, 0.0, 0.0, 0.0], [2, 100.0, 0.0, np.pi], [3, 900.0, 900.0, 1.0]]
FRAMES = [(PAIR, [[1, 2]]), (PAIR, [[1, 2, 42]])]


@pytest.fixture
def small(tmp_path) -> tuple[DatasetSpec, DatasetSpec]:
    shipped = _gcff(tmp_path / "shipped", FRAMES, settings={"stride": 50.0, "mdl": 10000.0})
    bare = _gcff(tmp_path / "bare", FRAMES)
    return (
        DatasetSpec(name="shipped", path=str(shipped)),
        DatasetSpec(name="bare", path=str(bare)),
    )


def test_every_detector_on_every_dataset(small):
    detectors = [detector_spec(s) for s in ("gcff", "gcff-own", "majority")]
    result = run_benchmark(small, detectors)
    shipped, bare = small
    own = result.cell(shipped, detectors[1])
    # Frame 1: {1, 2} found exactly; frame 2: {1, 2} against {1, 2, 42}: 2/3 matches, 1 misses.
    assert own.scores.at["2/3"] == (1.0, 1.0, 1.0)
    assert own.scores.at["1"] == (0.5, 0.5, 0.5)
    skipped = result.cell(bare, detectors[1])
    assert skipped.scores is None
    assert skipped.skipped == (
        "dataset 'bare': sequence 'bare' ships no GCFF settings (settings_gc.mat with stride and "
        "mdl)"
    )
    majority = result.cell(bare, detectors[2])
    assert majority.scores.at["2/3"] == (1.0, 0.0, 0.0)  # nothing detected: P = 1, R = 0
    means = result.means()
    assert means[detectors[1].label]["datasets"] == 1
    assert means[detectors[2].label]["2/3"] == (1.0, 0.0, 0.0)


def test_local_workers_give_the_same_cells(small):
    detectors = [detector_spec(s) for s in ("gcff", "gcff-own", "majority")]
    one = run_benchmark(small, detectors)
    two = run_benchmark(small, detectors, jobs=2)
    strip = [(c.dataset, c.detector, c.scores, c.skipped, c.predictions) for c in one.cells]
    assert strip == [(c.dataset, c.detector, c.scores, c.skipped, c.predictions) for c in two.cells]


def test_a_run_reads_each_dataset_once_for_its_cells_and_recordings(small, monkeypatch):
    read = []
    load = DatasetSpec.load
    monkeypatch.setattr(DatasetSpec, "load", lambda spec: read.append(spec.name) or load(spec))
    detectors = [detector_spec(s) for s in ("gcff", "gcff-own", "majority")]
    result = run_benchmark(small, detectors)
    assert sorted(read) == ["bare", "shipped"]
    assert [len(result.scored_frames(d)) for d in small] == [2, 2]
    assert sorted(read) == ["bare", "shipped"]  # the recordings' frames: the run's reading
    run_benchmark(small, detectors[2:])
    assert sorted(read) == ["bare", "bare", "shipped", "shipped"]  # a new run reads again


def test_test_split_scores_only_the_frames_training_leaves_out(tmp_path):
    folder = _gcff(tmp_path / "d", [(PAIR, [[1, 2]])] * 10)
    spec = DatasetSpec(name="d", path=str(folder), split="test", train_fraction=0.6)
    (cell,) = run_benchmark([spec], [detector_spec("majority")]).cells
    assert cell.dataset == "d (test split)" and cell.scores.frames == 4


def test_bad_arguments(small):
    with pytest.raises(ValueError, match=r"detectors must be distinct, got \['majority'\] twice"):
        run_benchmark(small, [detector_spec("majority")] * 2)
    with pytest.raises(ValueError, match=r"backend must be one of \('local', 'ray'\)"):
        run_benchmark(small, [detector_spec("majority")], backend="dask")
    with pytest.raises(ValueError, match=r"split must be 'all' or 'test', got 'train'"):
        DatasetSpec(name="x", path="x", split="train")


def test_own_settings_reproduce_the_original_gcff_code(shared_datasets):
    # The READMEs of coffeebreak/ and synth/: the original GCFF code with each sequence's own
    # settings, frame-mean protocol, F1 at T = 2/3 and T = 1.
    original = {
        ("coffeebreak", "Seq1"): (0.770, 0.451),
        ("coffeebreak", "Seq2"): (0.944, 0.731),
        ("synth", "synth"): (0.973, 0.909),
    }
    specs = [DatasetSpec(name=n, path=str(shared_datasets / n)) for n in ("coffeebreak", "synth")]
    result = run_benchmark(specs, [detector_spec("gcff-own")])
    for (dataset, sequence), (f1, f1_exact) in original.items():
        (cell,) = [c for c in result.cells if c.dataset == dataset]
        scores = cell.by_sequence[sequence]
        assert round(scores.at["2/3"][2], 3) == f1
        assert round(scores.at["1"][2], 3) == f1_exact


def _plugin(tmp_path: Path, monkeypatch, body: str) -> str:
    (tmp_path / "bench_plugin.py").write_text(textwrap.dedent(body))
    monkeypatch.syspath_prepend(str(tmp_path))
    sys.modules.pop("bench_plugin", None)
    return "bench_plugin:make"


def test_a_plugin_detector_runs_and_a_broken_one_is_named(small, tmp_path, monkeypatch):
    spec = _plugin(
        tmp_path,
        monkeypatch,
        """
        class Everyone:
            def predict(self, frames):
                return [(tuple(int(i) for i in f.ids),) for f in frames]

        class Forgetful:
            def predict(self, frames):
                return [(int(f.ids[0]),) for f in frames]  # the others are in no group

        def make():
            return Everyone()

        def broken():
            return Forgetful()
        """,
    )
    result = run_benchmark(small[:1], [detector_spec(spec)])
    # Everyone in one group: {1, 2, 3} against {1, 2}: 2/3 matches at T = 2/3.
    assert result.cells[0].scores.at["2/3"][2] == 1.0
    with pytest.raises(DetectorError, match=r"bench_plugin:broken.*frame"):
        run_benchmark(small[:1], [detector_spec("bench_plugin:broken")])


def test_cli_writes_the_tables_the_plot_and_the_recordings(small, tmp_path, capsys):
    from rerun.chunk import RrdReader

    shipped, bare = small
    out = tmp_path / "out"
    argv = ["benchmark", "--data", shipped.path, "--data", bare.path, "--out", str(out)]
    assert main([*argv, "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "## Per dataset" in printed and "## Mean over datasets" in printed
    assert "skipped: dataset 'bare'" in printed
    data = json.loads((out / "benchmark.json").read_text())
    assert [d["name"] for d in data["datasets"]] == ["shipped", "bare"]
    own = data["mean_over_datasets"]["GCFF, each dataset's own settings"]
    assert own["datasets"] == 1 and own["T=2/3"]["f1"] == 1.0
    assert (out / "benchmark.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    entities = {c.entity_path for c in RrdReader(out / "recordings" / "shipped.rrd").stream()}
    assert any(e.startswith("/world/groups/gcff-own") for e in entities)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["--data", "no-such-dataset"],
            "no-such-dataset: no such file or folder, nor a dataset name; the public datasets "
            "are: coffeebreak, cocktail-party",
        ),
        (["--detector", "nowhere.module:make"], "nowhere.module"),
        (["--backend", "local", "--address", "x"], "--address needs --backend ray"),
        (["--test-split", "slasa"], "--test-split slasa: expected the name of a dataset"),
    ],
    ids=["unknown-dataset", "plugin-that-does-not-import", "address-without-ray", "typo-split"],
)
def test_cli_bad_input_is_one_line(small, tmp_path, capsys, argv, message):
    if "--data" not in argv:
        argv = ["--data", small[0].path, *argv]
    assert main(["benchmark", *argv, "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("reform-sim benchmark: error: ") and message in err
    assert err.count("\n") == 1


@pytest.mark.slow
def test_ray_backend_gives_the_local_cells(small, ray_instance):
    detectors = [detector_spec(s) for s in ("gcff", "gcff-own", "majority")]
    local = run_benchmark(small, detectors)
    remote = run_benchmark(small, detectors, backend="ray")
    key = [(c.dataset, c.detector, c.scores, c.skipped, c.predictions) for c in local.cells]
    assert key == [
        (c.dataset, c.detector, c.scores, c.skipped, c.predictions) for c in remote.cells
    ]


def test_the_mean_over_common_datasets_compares_like_with_like(small):
    detectors = [detector_spec(s) for s in ("gcff-own", "majority")]
    result = run_benchmark(small, detectors)
    assert result.common_datasets() == ("shipped",)  # bare ships no settings
    common = result.means(result.common_datasets())
    assert common[detectors[1].label]["datasets"] == 1
    assert result.means()[detectors[1].label]["datasets"] == 2


def test_a_mean_over_the_datasets_found_counts_a_recording_once():
    found = ["coffeebreak", "cocktail-party", "synth", "cocktail-party-dante", "babble"]
    kept, lines = one_recording_each(found)
    assert kept == ["coffeebreak", "cocktail-party", "synth", "babble"]
    assert lines == [
        "cocktail-party-dante left out: the same recording as cocktail-party, which is scored "
        "(give --data cocktail-party-dante to score it)"
    ]
    assert one_recording_each(found, named={"cocktail-party-dante"}) == (found, [])


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_cli_finds_a_plugin_in_the_current_folder(small, tmp_path, monkeypatch, jobs):
    """As evaluate and detect do: `--detector mylab.detectors:Close` from the lab's folder,
    without PYTHONPATH, in the workers too."""
    lab = tmp_path / "lab"
    (lab / "benchlab").mkdir(parents=True)
    (lab / "benchlab" / "__init__.py").write_text("")
    (lab / "benchlab" / "detectors.py").write_text(
        textwrap.dedent(
            """
            class Close:
                def predict(self, frames):
                    return [[(int(i),) for i in f.ids] for f in frames]
            """
        )
    )
    monkeypatch.chdir(lab)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", str(lab))])
    out = tmp_path / f"out{jobs}"
    argv = ["benchmark", "--data", small[0].path, "--data", small[1].path]
    argv += ["--detector", "benchlab.detectors:Close", "--jobs", jobs]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    cells = json.loads((out / "benchmark.json").read_text())["cells"]
    assert len(cells) == 2 and all(c["scores"]["frames"] > 0 for c in cells)


class _EveryoneAlone:
    """A detector registered in the test's process only."""

    def predict(self, frames):
        return [[(int(i),) for i in f.ids] for f in frames]


def test_a_detector_registered_in_this_process_runs_in_the_workers(small, monkeypatch):
    import reform.detectors

    monkeypatch.setattr(reform.detectors, "_REGISTRY", dict(reform.detectors._REGISTRY))
    reform.detectors.register_detector("lab-alone", _EveryoneAlone)
    detectors = [detector_spec("lab-alone"), detector_spec("majority")]

    def cells(jobs):
        result = run_benchmark(small, detectors, jobs=jobs)
        return [(c.dataset, c.detector, c.scores, c.predictions) for c in result.cells]

    alone = cells(1)
    assert cells(2) == alone
    assert all(scores is not None for _, _, scores, _ in alone)


def test_a_detector_that_learns_is_scored_only_on_what_it_did_not_see(tmp_path):
    """gcff-tuned searches stride and mdl on the first 60 % of the frames by time and is scored
    on the other 40 %: four of ten frames, the cell labelled as the test split."""
    folder = _gcff(tmp_path / "d", [(PAIR, [[1, 2]])] * 10)
    spec = DatasetSpec(name="d", path=str(folder), train_fraction=0.6)
    tuned = detector_spec("gcff-tuned")
    assert tuned.learns and tuned.label == "GCFF, tuned on each dataset's training part"
    result = run_benchmark([spec], [tuned, detector_spec("majority")])
    cell = result.cell(spec, tuned)  # in the dataset's row, beside the others
    assert cell.scores.frames == 4 and result.cell(spec, result.detectors[1]).scores.frames == 10
    assert cell.scores.at["1"] == (1.0, 1.0, 1.0)


def test_all_is_every_catalogued_detector_without_a_model_file(tmp_path, capsys):
    from reform.detectors import builtin_names, detector_info

    names = builtin_names()
    assert {"gcff", "gcff-own", "gcff-tuned", "majority"} <= set(names)
    assert "reform" not in names  # read from a model file
    for name in names:
        assert detector_info(name).source == "built-in"


def test_blocks_are_contiguous_stretches_of_each_recording():
    from reform import Frame
    from sim.experiments.benchmark import bootstrap_blocks

    def frame(sequence, time):
        return Frame(
            ids=np.array([1]),
            position=np.zeros((1, 2)),
            yaw=np.zeros(1),
            sequence=sequence,
            time=time,
        )

    frames = [frame("a", t) for t in range(5)] + [frame("b", t) for t in range(2)]
    # hand-computed: a's 5 frames in 2 blocks (k * 2 // 5), b's 2 frames in 2 blocks
    assert bootstrap_blocks(frames, blocks=2) == ["a#0", "a#0", "a#0", "a#1", "a#1", "b#0", "b#1"]


def test_every_score_carries_its_bootstrap_interval(tmp_path):
    frames = [(PAIR, [[1, 2]])] * 6 + [(PAIR, [[1, 3]])] * 6
    folder = _gcff(tmp_path / "d", frames)
    spec = DatasetSpec(name="d", path=str(folder))
    one, two = run_benchmark([spec], [detector_spec("gcff"), detector_spec("proximity")]).cells
    for cell in (one, two):
        for t in ("2/3", "1"):
            low, high = cell.scores.f1_interval[t]
            assert low <= cell.scores.at[t][2] <= high
    assert one.scores.f1_interval["2/3"][0] < one.scores.f1_interval["2/3"][1]  # it varies


def test_temporal_scores_each_cells_events_as_evaluate_events_does(tmp_path):
    from toy_scenes import line_frame

    from reform import Dataset, make_detector, write_parquet
    from reform.seeding import Role, derive_rng
    from reform.temporal import evaluate_events

    # person 3 joins (1, 2) at 2 s and leaves at 4 s; frames 0.5 s apart
    frames = tuple(
        line_frame([1, 2, 3], [[1, 2, 3]] if 2.0 <= 0.5 * k < 4.0 else [[1, 2]], time=0.5 * k)
        for k in range(12)
    )
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=frames, name="toy", source="toy_scenes"), path)
    one = tmp_path / "one.parquet"
    write_parquet(Dataset(frames=frames[:1], name="one", source="toy_scenes"), one)
    datasets = [DatasetSpec(name="toy", path=str(path)), DatasetSpec(name="one", path=str(one))]
    benchmark = run_benchmark(datasets, [detector_spec("gcff")], temporal=True)
    cell = benchmark.cell(datasets[0], benchmark.detectors[0])
    unlabelled = [f.replace(groups=None) for f in frames]
    rng = derive_rng(0, Role.TEMPORAL_BOOTSTRAP, zlib.crc32(b"toy"))
    expected = evaluate_events(
        frames, make_detector("gcff").predict(unlabelled), tolerance_s=1.0, rng=rng
    ).to_json()
    assert cell.temporal == expected and expected["true_events"] == 2
    skipped = benchmark.cell(datasets[1], benchmark.detectors[0]).temporal
    assert "expected at least two" in skipped["skipped"]
    # without --temporal a cell holds none
    assert run_benchmark(datasets[:1], [detector_spec("gcff")]).cells[0].temporal is None


def test_the_report_has_a_groups_in_time_table(tmp_path, capsys):
    from toy_scenes import line_frame

    from reform import Dataset, write_parquet

    frames = tuple(
        line_frame([1, 2, 3], [[1, 2, 3]] if k >= 4 else [[1, 2]], time=float(k)) for k in range(8)
    )
    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=frames, name="toy", source="toy_scenes"), path)
    argv = ["benchmark", "--data", str(path), "--detector", "majority", "--temporal"]
    assert main([*argv, "--out", str(tmp_path / "out"), "--no-recordings", "-q"]) == 0
    report = (tmp_path / "out" / "benchmark.md").read_text()
    assert "## Groups in time" in report and "--temporal" in report
    row = next(
        line for line in report.splitlines() if line.startswith("| toy.parquet | majority | ")
    )
    assert row.split(" | ")[2:4] == ["1", "0.0"]  # one join, none found
    cell = json.loads((tmp_path / "out" / "benchmark.json").read_text())["cells"][0]
    assert cell["temporal"]["true_events"] == 1


def test_a_recording_holds_the_frames_every_detector_scored(small, tmp_path):
    # gcff-tuned learns on the first 3 of 5 frames and is scored on the last 2; majority on all
    # 5. The recording shows the 2 both scored, each detector's groups of those.
    from rerun.chunk import RrdReader

    five = _gcff(tmp_path / "five", FRAMES * 2 + FRAMES[:1])
    dataset = DatasetSpec(name="five", path=str(five))
    tuned, majority = (detector_spec(s) for s in ("gcff-tuned", "majority"))
    result = run_benchmark([dataset], [tuned, majority])
    frames, predictions = result.recorded(dataset)
    assert [f.time for f in frames] == [f.time for f in result.cell_frames(dataset, tuned)]
    assert len(frames) == 2 and len(result.cell_frames(dataset, majority)) == 5
    assert predictions[tuned.key] == list(result.cell(dataset, tuned).predictions)
    assert predictions[majority.key] == list(result.cell(dataset, majority).predictions[3:])
    out = tmp_path / "out"
    argv = ["benchmark", "--data", str(five), "--detector", "gcff-tuned", "--detector", "majority"]
    assert main([*argv, "--out", str(out), "--quiet"]) == 0
    entities = {c.entity_path for c in RrdReader(out / "recordings" / "five.rrd").stream()}
    assert any(e.startswith(f"/world/groups/{tuned.key}") for e in entities), entities


def test_the_plot_is_drawn_without_pyplot_and_no_recording_imports_no_rerun(small, tmp_path):
    out = tmp_path / "out"
    argv = ["benchmark", "--quiet", "--no-recordings", "--out", str(out)]
    argv += [w for spec in small for w in ("--data", spec.path)]
    code = (
        "import sys; from sim.cli import main; main(sys.argv[1:]); "
        "print(sorted({'matplotlib', 'matplotlib.pyplot', 'rerun'} & set(sys.modules)))"
    )
    run = subprocess.run(
        [sys.executable, "-c", code, *argv], capture_output=True, text=True, check=True
    )
    assert run.stdout.splitlines()[-1] == "['matplotlib']"
    assert (out / "benchmark.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

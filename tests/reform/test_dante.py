"""DANTE (reform.dante): the paper's folds, its dominant-set clustering, real training on tiny
toy scenes, determinism, the safetensors model file and its refusals, and the one-line message
when the extra reform-sim[dante] is not installed."""

from __future__ import annotations

import inspect
import json
import os
import re
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from field_scores import assert_same_groups_moved_and_relabelled
from toy_scenes import toy_frames

from reform import Dataset, DetectorError, Frame, Reform, detector_info, make_detector, save_model
from reform.classifiers import make_classifier
from reform.dante import Dante, affinity_matrix, dominant_sets, fold_splits, load_dante
from reform.datasets import write_parquet
from sim.cli import main

torch = pytest.importorskip("torch")
REPO = Path(__file__).resolve().parents[2]
TINY = {"epochs": 3, "batch_size": 256, "learning_rate": 1e-3}  # seconds, not minutes


@pytest.fixture(scope="module")
def trained() -> Dante:
    return Dante(**TINY, random_state=0).fit(toy_frames(0, 30))


@pytest.fixture(scope="module")
def model_path(trained, tmp_path_factory) -> Path:
    return trained.save(tmp_path_factory.mktemp("dante") / "dante.safetensors")


# ------------------------------------------------------------------------------------------------
# The paper's folds


def test_fold_splits_follow_dantes_build_dataset():
    # Hand-computed from build_dataset.py's rule for 20 frames, k = 5: folds of 4, half-fold 2.
    expected = [
        (list(range(8, 20)), [4, 5, 6, 7], [0, 1, 2, 3]),  # first: a whole fold after
        ([0, 1, *range(10, 20)], [2, 3, 8, 9], [4, 5, 6, 7]),
        ([*range(0, 6), *range(14, 20)], [6, 7, 12, 13], [8, 9, 10, 11]),
        ([*range(0, 10), 18, 19], [10, 11, 16, 17], [12, 13, 14, 15]),
        (list(range(0, 12)), [12, 13, 14, 15], [16, 17, 18, 19]),  # last: a whole fold before
    ]
    got = [tuple(part.tolist() for part in split) for split in fold_splits(20, 5)]
    assert got == expected
    by_frames = fold_splits(toy_frames(0, 20), 5)  # the frames themselves, or their count
    assert [tuple(part.tolist() for part in split) for split in by_frames] == expected


@pytest.mark.parametrize("n", [10, 119, 1143])
def test_every_frame_is_tested_once_and_the_parts_are_disjoint(n):
    splits = fold_splits(n)
    tested = np.concatenate([test for _, _, test in splits])
    assert sorted(tested.tolist()) == list(range(n))
    for train, validation, test in splits:
        parts = [set(train.tolist()), set(validation.tolist()), set(test.tolist())]
        assert sum(len(p) for p in parts) == len(set().union(*parts))


@pytest.mark.parametrize(
    ("n", "k", "message"),
    [(9, 5, r"n_frames must be at least 10 for 5 folds, got 9"), (20, 1, r"k must be an integer")],
    ids=["too-few-frames", "one-fold"],
)
def test_fold_splits_refuse_what_cannot_be_split(n, k, message):
    with pytest.raises(ValueError, match=message):
        fold_splits(n, k)


# ------------------------------------------------------------------------------------------------
# The clustering


def test_dominant_sets_peel_the_two_blocks():
    a = np.full((5, 5), 0.01)
    a[np.ix_([0, 1, 2], [0, 1, 2])] = 0.9
    a[np.ix_([3, 4], [3, 4])] = 0.8
    np.fill_diagonal(a, 0.0)
    assert [g.tolist() for g in dominant_sets(a)] == [[0, 1, 2], [3, 4]]


def test_people_left_over_are_grouped_while_any_affinity_joins_them():
    """DANTE's loop stops only when no affinity is left: two people left with a tiny affinity
    become a pair (its code's behaviour, kept; see docs/detectors/dante.md)."""
    a = np.zeros((4, 4))
    a[0, 1] = a[1, 0] = 0.95
    a[2, 3] = a[3, 2] = 1e-6
    assert [g.tolist() for g in dominant_sets(a)] == [[0, 1], [2, 3]]
    a[2, 3] = a[3, 2] = 0.0
    assert [g.tolist() for g in dominant_sets(a)] == [[0, 1]]


def test_affinity_matrix_averages_the_two_orders():
    # ordered pairs of 3 people: (0,1) (0,2) (1,0) (1,2) (2,0) (2,1)
    a = affinity_matrix(3, np.array([0.2, 0.4, 0.6, 0.8, 1.0, 0.0]))
    assert a.tolist() == [[0.0, 0.4, 0.7], [0.4, 0.0, 0.4], [0.7, 0.4, 0.0]]


# ------------------------------------------------------------------------------------------------
# Training and predicting


def test_a_trained_dante_finds_the_circles(trained):
    frames = toy_frames(1, 5)
    for frame, partition in zip(frames, trained.predict(frames), strict=True):
        found = {frozenset(g) for g in partition if len(g) > 1}
        assert {frozenset(g) for g in frame.groups} <= found


def test_one_seed_one_model_another_seed_another():
    frames = toy_frames(0, 12)
    scene = toy_frames(2, 1)[0]
    first = Dante(**TINY, random_state=3).fit(frames).affinities(scene)
    again = Dante(**TINY, random_state=3).fit(frames).affinities(scene)
    other = Dante(**TINY, random_state=4).fit(frames).affinities(scene)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, other)


def test_training_leaves_torch_global_state_as_it_was():
    torch.manual_seed(123)
    expected = torch.rand(3)
    torch.manual_seed(123)
    threads = torch.get_num_threads()
    Dante(**{**TINY, "epochs": 1}).fit(toy_frames(0, 4))
    assert torch.equal(torch.rand(3), expected)
    assert torch.get_num_threads() == threads


def test_validation_frames_stop_training_early():
    model = Dante(**{**TINY, "epochs": 40}, patience=1).fit(
        toy_frames(0, 8), validation=toy_frames(5, 4)
    )
    assert 2 <= len(model.history_) < 40
    assert all("validation_loss" in record for record in model.history_)


def test_progress_is_called_once_per_epoch():
    seen = []
    Dante(**TINY).fit(toy_frames(0, 4), progress=lambda *a: seen.append(a[:2]))
    assert seen == [(1, 3), (2, 3), (3, 3)]


def _frame(n: int, **kwargs) -> Frame:
    rng = np.random.default_rng(n)
    return Frame(
        ids=np.arange(10, 10 + n),
        position=rng.uniform(0, 3, (n, 2)),
        yaw=rng.uniform(-3, 3, n),
        **kwargs,
    )


def test_a_frame_predicted_in_pieces_gives_the_same_affinities(trained, monkeypatch):
    """Large frames are scored a few pairs at a time (memory stays bounded): same answer."""
    frame = toy_frames(4, 1)[0]
    whole = trained.affinities(frame)
    monkeypatch.setattr("reform.dante._PREDICT_PEOPLE", 3 * (frame.n_people - 2))  # 3 pairs
    np.testing.assert_allclose(trained.affinities(frame), whole, rtol=0, atol=1e-6)


def test_dense_scenes_keep_their_groups_turned_moved_and_relabelled(trained):
    assert_same_groups_moved_and_relabelled(trained, seed=41)


@pytest.mark.parametrize("n", [0, 1, 2, 3])
def test_nobody_one_two_and_three_people(trained, n):
    (partition,) = trained.predict([_frame(n)])
    assert sorted(p for group in partition for p in group) == list(range(10, 10 + n))
    assert trained.affinities(_frame(n)).shape == (n, n)


@pytest.mark.parametrize("orientation", ["head", "both"])
def test_a_missing_head_takes_the_body_orientation(orientation):
    frame = _frame(4)
    head_yaw = np.array([0.5, np.nan, -1.0, np.nan])
    head_position = np.where(np.isnan(head_yaw)[:, None], np.nan, frame.position)
    with_heads = _frame(4, head_position=head_position, head_yaw=head_yaw)
    filled = _frame(
        4, head_position=frame.position, head_yaw=np.where(np.isnan(head_yaw), frame.yaw, head_yaw)
    )
    model = Dante(**TINY, orientation=orientation).fit(toy_frames(0, 4))
    a = model.affinities(with_heads)
    assert np.isfinite(a).all()
    assert np.array_equal(a, model.affinities(filled))


def test_an_untrained_dante_says_how_to_train_it():
    with pytest.raises(ValueError, match=r"^this DANTE is not trained: fit it on annotated frames"):
        Dante().predict(toy_frames(0, 1))


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"orientation": "feet"}, r"orientation must be one of body, head, both, got 'feet'"),
        ({"epochs": 0}, r"epochs must be an integer of at least 1, got 0"),
        ({"dyad_widths": ()}, r"dyad_widths must be a non-empty sequence of layer widths"),
        ({"learning_rate": 0.0}, r"learning_rate must be in \(0, 1\], got 0.0"),
    ],
    ids=["orientation", "epochs", "widths", "learning-rate"],
)
def test_bad_parameters_are_named(params, message):
    with pytest.raises(ValueError, match=message):
        Dante(**params).fit(toy_frames(0, 2))


def test_frames_without_pairs_to_learn_from_are_refused():
    with pytest.raises(ValueError, match=r"needs annotated frames with two or more people"):
        Dante(**TINY).fit([_frame(1, groups=())])


# ------------------------------------------------------------------------------------------------
# The model file


def test_save_then_load_predicts_the_same(trained, model_path):
    loaded = load_dante(model_path)
    frames = toy_frames(3, 4)
    assert loaded.predict(frames) == trained.predict(frames)
    assert np.array_equal(loaded.affinities(frames[0]), trained.affinities(frames[0]))
    assert loaded.get_params() == trained.get_params()
    assert loaded.training_summary_ == trained.training_summary_


def test_the_file_is_safetensors_with_json_metadata(model_path):
    data = model_path.read_bytes()
    (length,) = struct.unpack("<Q", data[:8])
    header = json.loads(data[8 : 8 + length])
    metadata = json.loads(header["__metadata__"]["reform_sim"])
    assert metadata["format"] == "reform-sim dante model"
    assert metadata["params"]["dyad_widths"] == [16, 64]
    assert metadata["training"]["frames"] == 30


def test_the_catalogue_makes_dante_from_a_model_file(trained, model_path):
    detector = make_detector("dante", model=model_path)
    frames = toy_frames(3, 2)
    assert detector.predict(frames) == trained.predict(frames)
    with pytest.raises(DetectorError, match=r"^detector 'dante': epochs train a new model; model="):
        make_detector("dante", model=model_path, epochs=5)


def test_the_catalogue_declares_dantes_own_defaults():
    signature = inspect.signature(Dante).parameters
    for option in detector_info("dante").options:
        if option.name != "model":
            assert option.default == signature[option.name].default, option.name


def _rewritten(model_path: Path, folder: Path, change) -> Path:
    from safetensors.numpy import load, save

    data = model_path.read_bytes()
    (length,) = struct.unpack("<Q", data[:8])
    metadata = json.loads(data[8 : 8 + length])["__metadata__"]
    arrays = load(data)
    change(arrays)
    path = folder / "changed.safetensors"
    path.write_bytes(save(arrays, metadata=metadata))
    return path


def _written(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _reform_model(folder: Path) -> Path:
    model = Reform(make_classifier("logistic-regression")).fit(toy_frames(0, 10))
    return save_model(model, folder / "model.skops")


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (_reform_model, r"a REFORM model file \(skops archive\), not a DANTE model"),
        (
            lambda d: _written(d / "t.safetensors", b"\x10\x00"),
            r"not a DANTE model file \(not a safetensors file: too short\)",
        ),
        (
            lambda d: _written(d / "r.safetensors", bytes(range(64))),
            r"not a DANTE model file \(not a safetensors file",
        ),
        (lambda d: d, r"is a folder: expected a DANTE model"),
    ],
    ids=["reform-skops", "too-short", "random-bytes", "folder"],
)
def test_a_file_that_is_not_a_dante_model_is_refused_in_one_line(tmp_path, make, message):
    path = make(tmp_path)
    with pytest.raises(ValueError, match=message) as info:
        load_dante(path)
    assert "\n" not in str(info.value)
    with pytest.raises(DetectorError, match=r"^detector 'dante': .*" + message):
        make_detector("dante", model=path)


def test_a_corrupt_model_file_is_refused(model_path, tmp_path):
    data = model_path.read_bytes()
    truncated = tmp_path / "truncated.safetensors"
    truncated.write_bytes(data[: len(data) - 100])
    with pytest.raises(ValueError, match=r"truncated.safetensors: corrupt DANTE model file"):
        load_dante(truncated)

    def nan(arrays):
        arrays["logit.weight"] = np.full_like(arrays["logit.weight"], np.nan)

    with pytest.raises(ValueError, match=r"tensor logit.weight holds NaN or infinite values"):
        load_dante(_rewritten(model_path, tmp_path, nan))

    def narrow(arrays):
        arrays["logit.weight"] = arrays["logit.weight"][:, :3].copy()

    with pytest.raises(ValueError, match=r"tensor logit.weight is float32\[1, 3\], expected"):
        load_dante(_rewritten(model_path, tmp_path, narrow))

    with pytest.raises(ValueError, match=r"do not fit its network \(missing \['dyad.0"):
        load_dante(_rewritten(model_path, tmp_path, lambda a: a.pop("dyad.0.linear.bias")))


def test_a_safetensors_file_of_someone_else_is_refused(tmp_path):
    from safetensors.numpy import save_file

    path = tmp_path / "other.safetensors"
    save_file({"w": np.zeros(3, dtype=np.float32)}, path)
    with pytest.raises(ValueError, match=r"a safetensors file, but not a DANTE model"):
        load_dante(path)


def test_reform_refuses_a_dante_model_in_one_line(model_path):
    with pytest.raises(ValueError, match=r"a DANTE model file \(safetensors\), not a REFORM model"):
        make_detector("reform", model=model_path)


# ------------------------------------------------------------------------------------------------
# The command line


def test_train_dante_writes_a_model_that_evaluate_uses(tmp_path, capsys):
    data = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 12)), name="toy", source="toy_scenes"), data)
    out = tmp_path / "m.safetensors"
    argv = ["train", "--detector", "dante", "--data", str(data), "--out", str(out)]
    options = ["--option", "epochs=2", "--option", "batch_size=256", "--option", "random_state=1"]
    assert main([*argv, *options]) == 0
    captured = capsys.readouterr()
    assert "trained DANTE on 12 frames of toy" in captured.out
    assert "epoch 2/2: loss" in captured.err
    assert "epochs: 100%" in captured.err  # the bar, redrawn while an epoch runs
    assert load_dante(out).get_params()["random_state"] == 1
    assert (
        main(["evaluate", "--detector", "dante", "--option", f"model={out}", "--data", str(data)])
        == 0
    )


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            ["--classifier", "weighted-knn"],
            r"--classifier is an option of --detector reform, not of --detector dante",
        ),
        (
            ["--option", "epochs=0"],
            r"detector 'dante': option epochs expects an? int from 1 to 100,?000",
        ),
        (["--option", "epoch=3"], r"detector 'dante' has no option 'epoch'"),
        (["--option", "model=x"], r"--option model= names a trained model"),
    ],
    ids=["reform-option", "out-of-range", "unknown", "model"],
)
def test_train_dante_refuses_bad_options_in_one_line(tmp_path, capsys, extra, message):
    out = tmp_path / "m.safetensors"
    argv = ["train", "--detector", "dante", "--data", "nowhere", "--out", str(out)]
    assert main([*argv, *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("reform-sim train: error: ") and "\n" not in err
    assert re.search(message, err), err


# ------------------------------------------------------------------------------------------------
# Without the extra


# A finder first on sys.meta_path that finds no torch: `import torch` fails as when it is not
# installed (sys.modules["torch"] = None would also break libraries that look it up there).
_NO_TORCH = """
import sys


class _NoTorch:
    def find_spec(self, name, path=None, target=None):
        if name == "torch" or name.startswith("torch."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


sys.meta_path.insert(0, _NoTorch())
"""


def _without_torch(tmp_path: Path, argv: list[str]) -> subprocess.CompletedProcess:
    """``python argv`` in a child process where ``import torch`` fails, as on a core install."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(_NO_TORCH)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), str(REPO)])}
    return subprocess.run(
        [sys.executable, *argv], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120
    )


def test_without_torch_make_detector_says_how_to_install_it(tmp_path, model_path):
    code = textwrap.dedent(
        f"""
        import sys
        from reform import DetectorError, make_detector
        try:
            make_detector("dante", model={str(model_path)!r})
        except DetectorError as exc:
            print(exc)
        print("torch" in sys.modules)
        """
    )
    done = _without_torch(tmp_path, ["-c", code])
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        f"detector 'dante' (model={str(model_path)!r}) needs PyTorch, which is not installed: "
        'pip install "reform-sim[dante]"',
        "False",
    ]


def test_without_torch_train_dante_fails_in_one_line(tmp_path):
    data = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 3)), name="toy", source="toy_scenes"), data)
    out = "m.safetensors"
    argv = ["-m", "sim.cli", "train", "--detector", "dante", "--data", str(data), "--out", out]
    done = _without_torch(tmp_path, argv)
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "reform-sim train: error: --detector dante needs PyTorch, which is not installed: "
        'pip install "reform-sim[dante]"'
    )
    assert not (tmp_path / out).exists()


def test_importing_reform_and_listing_detectors_does_not_import_torch(tmp_path):
    code = (
        "import sys, reform, reform.dante; reform.detector_names(); "
        "print(sorted(m for m in sys.modules if m == 'torch' or m.startswith('torch.')))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_benchmark_takes_a_dante_model_file(model_path, tmp_path):
    from sim.experiments.benchmark import DatasetSpec, model_spec, run_benchmark

    data = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(5, 12)), name="toy", source="toy"), data)
    spec = model_spec(model_path)
    assert spec.label == "DANTE (dante)" and not spec.learns
    (cell,) = run_benchmark([DatasetSpec(name="toy", path=str(data))], [spec]).cells
    assert cell.scores is not None and cell.scores.frames == 12
    wrong = tmp_path / "not-dante.safetensors"
    wrong.write_bytes(b"not a model")
    with pytest.raises(DetectorError):
        model_spec(wrong)

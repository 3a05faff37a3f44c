"""Any bytes in a dataset's files give a dataset or one clean DataFormatError, never a traceback.

Property-based: hypothesis writes byte strings, or near-valid text built from the formats'
own tokens, into each format's files and loads them.
"""

from __future__ import annotations

import io
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from reform import DataFormatError, Dataset
from reform.datasets import load_dataset

SETTINGS = settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)

# Tokens of the DANTE text format, and others that break it.
DANTE_TOKENS = st.sampled_from(
    [
        "ID_001",
        "ID_002",
        "ID_0010",
        "fake",
        "<",
        ">",
        "0.2",
        "3.2",
        "1.5",
        "-2",
        "nan",
        "inf",
        "1e309",
        "ID_",
        "ID_x",
        "",
        "\t",
        "é",
        "\x00",
        "999999999999999999999",
        "-0.0",
        "1e-320",
    ]
)


def _line(tokens: list[str]) -> str:
    return " ".join(tokens)


DANTE_LINES = st.lists(st.lists(DANTE_TOKENS, max_size=14).map(_line), max_size=6).map(
    lambda lines: "\n".join(lines) + "\n"
)


def _load(folder: Path, **kwargs) -> None:
    try:
        dataset = load_dataset(folder, **kwargs)
    except DataFormatError as exc:
        message = str(exc)
        assert "\n" not in message and len(message) < 2000, message
        return
    assert isinstance(dataset, Dataset)


def _load_files(files: dict[str, bytes | str], **kwargs) -> None:
    """Writes ``files`` (name -> bytes, or text) into a fresh folder and loads it (`_load`)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, content in files.items():
            if isinstance(content, str):
                (folder / name).write_text(content)
            else:
                (folder / name).write_bytes(content)
        _load(folder, **kwargs)


@SETTINGS
@given(
    features=st.one_of(st.binary(max_size=400), DANTE_LINES.map(str.encode)),
    groups=st.one_of(st.binary(max_size=200), DANTE_LINES.map(str.encode)),
)
def test_dante_files(features, groups):
    _load_files({"features.txt": features, "group_names.txt": groups}, format="dante")


def _valid_dante() -> tuple[str, str]:
    features = "0.2 ID_001 1.0 1.0 0.0 0.0 ID_002 1.6 1.0 3.1 3.1\n3.2 ID_001 1.0 1.0 0.0 0.0\n"
    groups = "0.2 < ID_001 ID_002 >\n3.2 < ID_001 >\n"
    return features, groups


@SETTINGS
@given(position=st.integers(0, 200), value=st.binary(min_size=1, max_size=8))
def test_dante_files_with_one_splice(position, value):
    features, groups = _valid_dante()
    data = features.encode()
    data = data[:position] + value + data[position:]
    _load_files({"features.txt": data, "group_names.txt": groups}, format="dante")


def _mat_bytes(variables: dict) -> bytes:
    buffer = io.BytesIO()
    scipy.io.savemat(buffer, variables)
    return buffer.getvalue()


def _cell(items) -> np.ndarray:
    array = np.empty((1, len(items)), dtype=object)
    for k, item in enumerate(items):
        array[0, k] = item
    return array


NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.integers(-(10**6), 10**6).map(float),
)
MATRICES = st.lists(st.lists(NUMBERS, min_size=0, max_size=5), max_size=4).map(
    lambda rows: np.array(rows, dtype=object if len({len(r) for r in rows}) > 1 else float)
)


@SETTINGS
@given(
    features=st.lists(MATRICES, max_size=3),
    stamps=st.lists(NUMBERS, max_size=4),
    groups=st.lists(st.lists(st.lists(NUMBERS, max_size=3), max_size=3), max_size=3),
    gt_stamps=st.lists(NUMBERS, max_size=4),
    units=st.sampled_from([None, "m", "cm"]),
)
def test_gcff_mat_variables(features, stamps, groups, gt_stamps, units):
    try:
        feature_bytes = _mat_bytes(
            {"features": _cell(features), "timestamp": np.array([stamps], dtype=float)}
        )
        gt = _cell([_cell([np.array([g], dtype=float) for g in frame]) for frame in groups])
        gt_bytes = _mat_bytes({"GTgroups": gt, "GTtimestamp": np.array([gt_stamps], dtype=float)})
    except (ValueError, TypeError):
        return  # scipy cannot write this combination: nothing to load
    _load_files(
        {"features.mat": feature_bytes, "groundtruth.mat": gt_bytes}, format="gcff", units=units
    )


@SETTINGS
@given(features=st.binary(max_size=600), groundtruth=st.binary(max_size=300))
def test_gcff_mat_bytes(features, groundtruth):
    _load_files({"features.mat": features, "groundtruth.mat": groundtruth}, format="gcff")


@SETTINGS
@given(position=st.integers(0, 1500), value=st.binary(min_size=1, max_size=6))
def test_gcff_mat_with_one_splice(position, value):
    feature_bytes = _mat_bytes(
        {
            "features": _cell([np.array([[1, 0.0, 0.0, 0.0], [2, 100.0, 0.0, 3.1]])]),
            "timestamp": np.array([[1.0]]),
        }
    )
    gt_bytes = _mat_bytes(
        {"GTgroups": _cell([_cell([np.array([[1.0, 2.0]])])]), "GTtimestamp": np.array([[1.0]])}
    )
    data = feature_bytes[:position] + value + feature_bytes[position + len(value) :]
    _load_files({"features.mat": data, "groundtruth.mat": gt_bytes}, format="gcff")


@SETTINGS
@given(motion=st.binary(max_size=800), annotations=st.binary(max_size=120))
def test_babble_files(motion, annotations):
    _load_files(
        {"Motion-capture-data.csv": motion, "annotated-frames.csv": annotations}, format="babble"
    )


@pytest.mark.parametrize("size", [0, 1, 100, 5000])
def test_parquet_garbage(tmp_path, size):
    rng = np.random.default_rng(size)
    path = tmp_path / "x.parquet"
    path.write_bytes(b"PAR1" + rng.bytes(size) + b"PAR1")
    _load(path)


# --------------------------------------------------------------------------------------------
# Mutations of real small files, Parquet and generated folders, detection, and the CLI's
# conversion (a file whole or not at all).


def _splice(data: bytes, position: int, value: bytes, replace: bool) -> bytes:
    position = position % (len(data) + 1)
    end = position + len(value) if replace else position
    return data[:position] + value + data[end:]


SPLICES = {
    "position": st.integers(0, 10**6),
    "value": st.binary(min_size=1, max_size=8),
    "replace": st.booleans(),
}


def _babble_head(babble_dir: Path) -> tuple[bytes, bytes]:
    lines = (babble_dir / "Motion-capture-data.csv").read_bytes().splitlines(keepends=True)
    return b"".join(lines[:21]), b"16,{[1 2 3 4 5 6 7]}\n"


@SETTINGS
@given(**SPLICES)
def test_babble_files_with_one_splice(babble_dir, position, value, replace):
    motion, annotations = _babble_head(babble_dir)
    _load_files(
        {
            "Motion-capture-data.csv": _splice(motion, position, value, replace),
            "annotated-frames.csv": annotations,
        },
        format="babble",
    )


def _small_dataset() -> Dataset:
    from reform import Frame

    frames = (
        Frame(
            ids=[1, 2, 3],
            position=[[0.0, 0.0], [1.0, 0.0], [3.0, 3.0]],
            yaw=[0.0, 3.1, -1.5],
            groups=((1, 2), (3,)),
            time=0.0,
        ),
        Frame(ids=[], position=np.zeros((0, 2)), yaw=[], time=0.5),
        Frame(ids=[2], position=[[1.0, 0.5]], yaw=[1.0], time=1.0),
    )
    return Dataset(frames=frames, name="small", metadata={"note": "é"})


@pytest.fixture(scope="module")
def parquet_bytes(tmp_path_factory) -> bytes:
    from reform.datasets import write_parquet

    path = write_parquet(_small_dataset(), tmp_path_factory.mktemp("pq") / "small.parquet")
    return path.read_bytes()


@SETTINGS
@given(data=st.binary(max_size=600))
def test_parquet_bytes(data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "x.parquet"
        path.write_bytes(data)
        _load(path)


@SETTINGS
@given(**SPLICES)
def test_parquet_with_one_splice(parquet_bytes, position, value, replace):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "x.parquet"
        path.write_bytes(_splice(parquet_bytes, position, value, replace))
        _load(path)


def test_a_column_name_that_is_not_utf8_is_one_line(parquet_bytes, tmp_path):
    """The first byte of a column name in the file's schema (``group``, a length-prefixed
    string) turned into one that UTF-8 cannot start with: found by the splice above."""
    path = tmp_path / "x.parquet"
    where = parquet_bytes.index(b"\x05group\x00") + 1
    path.write_bytes(_splice(parquet_bytes, where, b"\x80", True))
    with pytest.raises(DataFormatError) as caught:
        load_dataset(path)
    assert str(caught.value) == (
        f"{path}: field 'column names': expected UTF-8 text, "
        "found bytes that are not (invalid start byte)"
    )


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> tuple[Path, int]:
    """A real folder of ``generate``: two short episodes, and its frame count."""
    from sim.generate import generate_dataset

    folder = tmp_path_factory.mktemp("gen") / "d"
    generate_dataset(
        "mingle", episodes=2, seed=3, out_dir=folder, n_jobs=1, duration=2.0, progress=False
    )
    return folder, len(load_dataset(folder))


def _copy(folder: Path, into: Path) -> Path:
    import shutil

    return Path(shutil.copytree(folder, into / "copy"))


@settings(SETTINGS, max_examples=25)
@given(target=st.integers(0, 2), **SPLICES)
def test_generated_folder_with_one_splice(generated, target, position, value, replace):
    """The card or a shard spliced: the folder reads whole (every frame) or is refused, naming
    the file; never read with fewer frames."""
    from reform.datasets.parquet import verify_folder

    folder, n_frames = generated
    with tempfile.TemporaryDirectory() as tmp:
        copy = _copy(folder, Path(tmp))
        files = [copy / "dataset.json", *sorted(copy.rglob("*.parquet"))]
        path = files[target % len(files)]
        data = path.read_bytes()
        changed = _splice(data, position, value, replace)
        path.write_bytes(changed)
        try:
            dataset = load_dataset(copy)
        except DataFormatError as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 2000
        else:
            assert len(dataset) == n_frames  # nothing lost in silence
            assert path.name == "dataset.json" or changed == data
        try:
            problems = verify_folder(copy)
        except DataFormatError as exc:  # a card it cannot read
            problems = [str(exc)]
        assert all("\n" not in p for p in problems)
        if path.name != "dataset.json":
            assert bool(problems) == (changed != data)  # an altered shard is always named


NAMES = st.sampled_from(
    [
        "features.txt",
        "group_names.txt",
        "Motion-capture-data.csv",
        "annotated-frames.csv",
        "features.mat",
        "groundtruth.mat",
        "a.parquet",
        "dataset.json",
        "sub/features.mat",
        "sub/groundtruth.mat",
        "scenario=x/episode=0/part.parquet",
    ]
)


@SETTINGS
@given(files=st.dictionaries(NAMES, st.binary(max_size=200), max_size=5))
def test_detection_of_any_folder(files):
    """Any set of the formats' file names holding any bytes: a format and a dataset, or one
    clean error, from detection and from loading."""
    from reform.datasets import detect_format

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "d"
        folder.mkdir()
        for name, data in files.items():
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            (folder / name).write_bytes(data)
        try:
            assert detect_format(folder) in ("salsa", "babble", "gcff", "parquet")
        except DataFormatError as exc:
            assert "\n" not in str(exc)
        _load(folder)


@SETTINGS
@given(features=st.one_of(st.binary(max_size=300), DANTE_LINES.map(str.encode)))
def test_convert_writes_a_whole_file_or_none(features, capsys):
    """``reform-sim data convert``: exit 0 and a file that reads back as the input, or exit 2,
    one line, and no file (never a partial write)."""
    from reform.datasets import read_parquet
    from sim.cli import main

    _, groups = _valid_dante()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "in"
        folder.mkdir()
        (folder / "features.txt").write_bytes(features)
        (folder / "group_names.txt").write_text(groups)
        out = Path(tmp) / "out" / "x.parquet"
        status = main(
            ["data", "convert", "--data", str(folder), "--format", "dante", "--out", str(out)]
        )
        err = capsys.readouterr().err
        if status == 0:
            assert read_parquet(out).frames == load_dataset(folder, format="dante").frames
        else:
            assert status == 2 and len(err.strip().splitlines()) == 1, err
            assert not out.exists()  # no file, and no temporary beside it
            assert not out.parent.exists() or not any(out.parent.iterdir())

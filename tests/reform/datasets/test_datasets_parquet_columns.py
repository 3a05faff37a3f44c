"""The Parquet reader checks and builds a file's frames from whole columns; reading the same
file frame by frame (each frame checked and made on its own, the reader's way of naming a
fault) gives, for every file, the same result: the same frames, value for value, bit for bit
and type for type, or the same refusal, word for word."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from reform import DataFormatError, Dataset, Frame, FrameBlock
from reform.datasets import _parquet_read, read_parquet, write_parquet

_ARRAYS = ("ids", "position", "yaw", "head_position", "head_yaw")


def _read(path: Path) -> Dataset | str:
    """The dataset at ``path``, or its refusal's message."""
    try:
        return read_parquet(path)
    except DataFormatError as exc:
        return f"refused: {exc}"


def _read_frame_by_frame(path: Path, monkeypatch: pytest.MonkeyPatch) -> Dataset | str:
    """As `_read`, every frame checked and made on its own."""
    with monkeypatch.context() as patch:
        patch.setattr(_parquet_read, "_frames_from_columns", lambda *args: None)
        return _read(path)


def _read_by_columns(path: Path, monkeypatch: pytest.MonkeyPatch) -> Dataset:
    """The dataset at ``path``, read from whole columns (failing if it is read frame by frame)."""

    def refused(*args):
        raise AssertionError("the file was read frame by frame")

    with monkeypatch.context() as patch:
        patch.setattr(_parquet_read, "_frames_one_by_one", refused)
        return read_parquet(path)


def _assert_identical(a: Dataset | str, b: Dataset | str) -> None:
    """``a`` and ``b`` are the same refusal, or datasets whose every field has the same type
    and value (arrays: dtype, shape, bytes, read-only; floats: bits)."""
    if isinstance(a, str) or isinstance(b, str):
        assert a == b
        return
    assert (a.name, a.source, a.units, dict(a.metadata)) == (
        b.name,
        b.source,
        b.units,
        dict(b.metadata),
    )
    assert len(a.frames) == len(b.frames)
    for k, (x, y) in enumerate(zip(a.frames, b.frames, strict=True)):
        for name in _ARRAYS:
            u, v = getattr(x, name), getattr(y, name)
            assert (u is None) == (v is None), (k, name)
            if u is not None:
                assert (u.dtype, u.shape) == (v.dtype, v.shape), (k, name)
                assert u.tobytes() == v.tobytes(), (k, name)
                assert not u.flags.writeable and not v.flags.writeable, (k, name)
                assert u.flags.c_contiguous and v.flags.c_contiguous, (k, name)
        assert x.kinds == y.kinds and type(x.kinds) is type(y.kinds) is tuple, k
        assert all(type(kind) is str for kind in x.kinds + y.kinds), k
        for name in ("groups", "listed_groups"):
            u, v = getattr(x, name), getattr(y, name)
            assert u == v, (k, name)
            for groups in (u, v):
                if groups is not None:
                    assert type(groups) is tuple and all(type(g) is tuple for g in groups)
                    assert all(type(m) is int for g in groups for m in g), (k, name)
        assert type(x.time) is type(y.time) is float, k
        assert math.copysign(1, x.time) == math.copysign(1, y.time) and x.time == y.time, k
        assert x.sequence == y.sequence and type(x.sequence) is type(y.sequence) is str, k
    assert a.frames == b.frames


def _random_dataset(rng: np.random.Generator, *, n_frames: int) -> Dataset:
    """Frames of every shape the format keeps apart: nobody, heads or none (some unobserved),
    robots, groups in any member order, frames not annotated, ground truth naming people who
    are absent, two sequences interleaved, runs of frames of one size."""
    frames = []
    times = {"a": 0.0, "b": -3.0}
    n = int(rng.integers(0, 6))
    for _ in range(n_frames):
        if rng.random() < 0.3:
            n = int(rng.integers(0, 6))  # else the same size as the frame before
        sequence = str(rng.choice(["a", "b"]))
        times[sequence] += float(rng.choice([0.25, 1 / 3, 1e-9]))
        ids = rng.choice(40, size=n, replace=False)
        heads = rng.random() < 0.7
        observed = rng.random(n) < 0.8
        head_position = np.where(observed[:, None], rng.uniform(-9, 9, (n, 2)), np.nan)
        groups = listed = None
        if rng.random() < 0.8:
            order = rng.permutation(ids).tolist()
            cuts = sorted(rng.integers(0, n + 1, size=int(rng.integers(0, 4))).tolist())
            bounds = [0, *cuts, n]
            groups = tuple(tuple(order[a:b]) for a, b in itertools.pairwise(bounds) if b > a)
            pairs = [g for g in groups if len(g) >= 2]
            if pairs and rng.random() < 0.3:  # someone the tracker lost, named by the truth
                listed = tuple(g + (100 + k,) if k == 0 else g for k, g in enumerate(pairs))
        frames.append(
            Frame(
                ids=ids,
                kinds=tuple(rng.choice(["human", "robot"], p=[0.8, 0.2], size=n).tolist()),
                position=rng.normal(0, 5, (n, 2)),
                yaw=rng.uniform(-np.pi, np.pi, n),
                head_position=head_position if heads else None,
                head_yaw=np.where(observed, rng.uniform(-np.pi, np.pi, n), np.nan)
                if heads
                else None,
                groups=groups,
                listed_groups=listed,
                time=times[sequence],
                sequence=sequence,
            )
        )
    return Dataset(frames=tuple(frames), name="random", source="test", metadata={"k": [1, 2]})


def test_real_datasets_read_from_columns_as_frame_by_frame(
    tmp_path, monkeypatch, salsa_dataset, babble_dataset
):
    for dataset in (salsa_dataset, babble_dataset):
        path = write_parquet(dataset, tmp_path / f"{dataset.name}.parquet")
        by_columns = _read_by_columns(path, monkeypatch)
        _assert_identical(by_columns, _read_frame_by_frame(path, monkeypatch))
        assert by_columns.frames == dataset.frames


@pytest.mark.parametrize("seed", range(12))
def test_random_datasets_read_from_columns_as_frame_by_frame(tmp_path, monkeypatch, seed):
    dataset = _random_dataset(np.random.default_rng(seed), n_frames=40)
    path = write_parquet(dataset, tmp_path / "random.parquet")
    by_columns = _read_by_columns(path, monkeypatch)
    _assert_identical(by_columns, _read_frame_by_frame(path, monkeypatch))
    assert by_columns.frames == dataset.frames


def test_a_generated_block_reads_from_columns_as_frame_by_frame(tmp_path, monkeypatch):
    rng = np.random.default_rng(3)
    t, n = 60, 5
    present = np.ones((t, n), dtype=bool)
    present[:10, 3:] = False  # two walk in late
    present[30:34, :] = False  # the scene empties for a while
    present[40:, 0] = False  # one leaves
    declared = ((0, 1), (2, 3, 4))
    block = FrameBlock(
        time=np.arange(t) * 0.1,
        ids=np.arange(n),
        kinds=("robot", "human", "human", "human", "human"),
        present=present,
        position=rng.normal(0, 3, (t, n, 2)),
        yaw=rng.uniform(-np.pi, np.pi, (t, n)),
        head_position=rng.normal(0, 3, (t, n, 2)),
        head_yaw=rng.uniform(-np.pi, np.pi, (t, n)),
        groups=tuple(None if k % 7 == 0 else declared for k in range(t)),
        sequence="walk-0",
    )
    path = write_parquet(block, tmp_path / "part.parquet", name="walk")
    by_columns = _read_by_columns(path, monkeypatch)
    _assert_identical(by_columns, _read_frame_by_frame(path, monkeypatch))
    assert by_columns.frames == tuple(block.frames())


# --- altered files: refused with the same words, or read the same ---------------------------

_VALUES = {
    "string": [None, "robot", "giraffe", "b"],
    "int64": [None, 0, 2, -1],
    "int32": [None, 0, 1, -1, 3],
    "float64": [None, float("nan"), -0.0, 4.0],
    "bool": [None, True, False],
}


def _altered(table: pa.Table, cells: list[tuple[str, int, object]]) -> pa.Table:
    """``table`` with each ``(column, row, value)`` of ``cells`` set (columns made nullable)."""
    for name, row, value in cells:
        values = table.column(name).to_pylist()
        values[row] = value
        index = table.schema.get_field_index(name)
        field = table.schema.field(name)
        table = table.set_column(
            index, pa.field(name, field.type), pa.array(values, type=field.type)
        )
    return table


def _cases(table: pa.Table, rng: np.random.Generator) -> list[list[tuple[str, int, object]]]:
    """Every cell of ``table`` set to each value of its type, and 300 random pairs and
    triples of such changes."""
    single = [
        [(name, row, value)]
        for name, (type_name, *_) in _parquet_read.COLUMNS.items()
        for row in range(table.num_rows)
        for value in _VALUES[type_name]
    ]
    several = [
        [single[int(k)][0] for k in rng.choice(len(single), size=int(rng.integers(2, 4)))]
        for _ in range(300)
    ]
    return single + several


def _small_dataset() -> Dataset:
    """Thirteen rows holding each case: heads (one unobserved) or none, a robot, groups out of
    row order, a frame not annotated, frames with nobody (annotated with heads, or neither),
    two sequences, truth naming someone absent."""
    nan = np.nan
    frames = (
        Frame(
            ids=[5, 2, 9, 1],
            kinds=("human", "human", "robot", "human"),
            position=[[0.1, 0.2], [1.0, -1.0], [2.5, 0.0], [1 / 3, 2 / 7]],
            yaw=[0.0, -np.pi, 3.0, 1e-300],
            head_position=[[0.1, 0.25], [nan, nan], [2.5, 0.1], [0.3, 0.3]],
            head_yaw=[0.1, nan, 3.1, -0.2],
            groups=((9, 5), (1,), (2,)),
            time=0.0,
            sequence="a",
        ),
        Frame(ids=[1, 2], position=[[0, 0], [1, 1]], yaw=[0.5, -0.5], time=0.5, sequence="a"),
        Frame(
            ids=[],
            position=np.zeros((0, 2)),
            yaw=[],
            head_position=np.zeros((0, 2)),
            head_yaw=[],
            groups=(),
            time=1.0,
            sequence="a",
        ),
        Frame(ids=[], position=np.zeros((0, 2)), yaw=[], time=2.0, sequence="b"),
        Frame(
            ids=[7, 8, 3],
            position=[[0, 0], [0.7, 0], [3, 3]],
            yaw=[0, np.pi, 1],
            groups=((8, 7),),
            listed_groups=((8, 7, 4),),
            time=2.5,
            sequence="b",
        ),
        Frame(
            ids=[7, 8],
            position=[[0, 0], [0.7, 0]],
            yaw=[0, np.pi],
            head_position=[[0, 0.1], [0.7, 0.1]],
            head_yaw=[0.1, 3.0],
            groups=((7, 8),),
            time=1.5,
            sequence="a",
        ),
    )
    return Dataset(frames=frames, name="small", metadata={"seed": 7})


def test_every_altered_file_is_refused_or_read_as_frame_by_frame(tmp_path, monkeypatch):
    table = pq.read_table(write_parquet(_small_dataset(), tmp_path / "good.parquet"))
    assert table.num_rows == 13
    outcomes = {"read": 0, "refused": 0}
    for k, cells in enumerate(_cases(table, np.random.default_rng(2))):
        path = tmp_path / f"altered-{k}.parquet"
        pq.write_table(_altered(table, cells), path)
        by_columns = _read(path)
        _assert_identical(by_columns, _read_frame_by_frame(path, monkeypatch))
        outcomes["refused" if isinstance(by_columns, str) else "read"] += 1
        path.unlink()
    # Both kinds of file were met: files read (their frames compared) and files refused.
    assert outcomes["read"] > 200 and outcomes["refused"] > 200, outcomes


def _rewritten(path: Path, out: Path, *, kind: pa.DataType, row_group_size: int) -> Path:
    """The file at ``path`` written again, its ``kind`` column cast to ``kind`` (its dictionary
    encoded with ``pa.dictionary``), in row groups of ``row_group_size`` rows."""
    table = pq.read_table(path)
    index = table.schema.get_field_index("kind")
    column = table.column("kind")
    column = column.dictionary_encode() if pa.types.is_dictionary(kind) else column.cast(kind)
    table = table.set_column(index, "kind", column)
    pq.write_table(table, out, row_group_size=row_group_size)
    return out


def test_text_columns_read_the_same_however_a_file_stores_them(tmp_path, monkeypatch):
    """Text columns are read as codes into their texts: the same frames from large strings and
    from row groups whose dictionaries differ; a column whose own type is a dictionary is refused
    by its type, as it always was."""
    dataset = _random_dataset(np.random.default_rng(5), n_frames=40)
    path = write_parquet(dataset, tmp_path / "random.parquet")
    large = _rewritten(path, tmp_path / "large.parquet", kind=pa.large_string(), row_group_size=7)
    by_columns = _read_by_columns(large, monkeypatch)
    _assert_identical(by_columns, _read_frame_by_frame(large, monkeypatch))
    assert by_columns.frames == dataset.frames
    coded = pa.dictionary(pa.int32(), pa.string())
    stored = _rewritten(path, tmp_path / "coded.parquet", kind=coded, row_group_size=1000)
    with pytest.raises(DataFormatError, match=r"kind.*type string.*dictionary<values=string"):
        read_parquet(stored)

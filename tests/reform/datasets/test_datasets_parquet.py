"""The project's Parquet format: exact round trips, shard folders, malformed files."""

from __future__ import annotations

import gzip
import hashlib
import json
import re
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from dataset_refusals import assert_refused_by_each
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from reform import DataFormatError, Dataset, Frame
from reform.datasets import _parquet_read, detect_format, load_babble, load_dataset, load_salsa
from reform.datasets.parquet import (
    COLUMNS,
    FORMAT_VERSION,
    METADATA_KEY,
    read_parquet,
    write_parquet,
)


def _same(a: Dataset, b: Dataset) -> None:
    assert a.frames == b.frames
    assert (a.name, a.source, a.units) == (b.name, b.source, b.units)
    assert dict(a.metadata) == dict(b.metadata)


def _mixed_dataset() -> Dataset:
    """Every case the format must keep apart."""
    nan = np.nan
    frames = [
        # heads, one unobserved; a robot; groups whose member order differs from the row order
        Frame(
            ids=[5, 2, 9, 1],
            kinds=("human", "human", "robot", "human"),
            position=[[0.1, 0.2], [1.0, -1.0], [2.5, 0.0], [1 / 3, 2 / 7]],
            yaw=[0.0, -np.pi, 3.0, 1e-300],
            head_position=[[0.1, 0.25], [nan, nan], [2.5, 0.1], [0.3, 0.3]],
            head_yaw=[0.1, nan, 3.1, -0.2],
            groups=((9, 5), (1,), (2,)),
            time=0.0,
            sequence="episode-a",
        ),
        # no heads at all (None, not NaN); annotated with no F-formation
        Frame(
            ids=[1, 2],
            position=[[0, 0], [1, 1]],
            yaw=[0.5, -0.5],
            groups=(),
            time=0.5,
            sequence="episode-a",
        ),
        # not annotated
        Frame(ids=[3], position=[[4, 4]], yaw=[1.0], time=1.0, sequence="episode-a"),
        # nobody: annotated, with (empty) heads
        Frame(
            ids=[],
            position=np.zeros((0, 2)),
            yaw=[],
            head_position=np.zeros((0, 2)),
            head_yaw=[],
            groups=(),
            time=1.5,
            sequence="episode-a",
        ),
        # nobody, not annotated, no heads
        Frame(ids=[], position=np.zeros((0, 2)), yaw=[], time=2.0, sequence="episode-b"),
        Frame(
            ids=[7, 8],
            position=[[0, 0], [0.7, 0]],
            yaw=[0, np.pi],
            groups=((8, 7),),
            time=2.5,
            sequence="episode-b",
        ),
    ]
    return Dataset(
        frames=tuple(frames),
        name="mixed",
        source="hand-written test frames",
        metadata={"seed": 7, "parameters": {"stride_m": 0.7, "names": ["a", "b"]}},
    )


def test_round_trip_is_exact(tmp_path):
    dataset = _mixed_dataset()
    path = write_parquet(dataset, tmp_path / "mixed.parquet")
    back = read_parquet(path)
    _same(back, dataset)
    assert back[0].groups == ((9, 5), (1,), (2,))
    assert back[1].head_position is None
    assert back[3].n_people == 0 and back[3].head_position is not None and back[3].groups == ()
    assert back[4].n_people == 0 and back[4].head_position is None and back[4].groups is None
    assert back[0].kinds == ("human", "human", "robot", "human")


def test_schema_metadata_and_columns(tmp_path):
    path = write_parquet(_mixed_dataset(), tmp_path / "mixed.parquet")
    schema = pq.read_schema(path)
    assert schema.names == list(COLUMNS)
    header = json.loads(schema.metadata[METADATA_KEY])
    assert header["format_version"] == FORMAT_VERSION
    assert header["generator_version"].startswith("reform-sim ")
    assert header["name"] == "mixed" and header["units"] == "m"
    assert schema.field("x").metadata[b"unit"] == b"m"
    table = pq.read_table(path)
    assert table.num_rows == 4 + 2 + 1 + 1 + 1 + 2  # an empty frame keeps one row
    assert table.column("person_id").null_count == 2


def test_real_datasets_round_trip(tmp_path, salsa_dir, babble_dir):
    for dataset in (load_salsa(salsa_dir), load_babble(babble_dir)):
        path = write_parquet(dataset, tmp_path / f"{dataset.name}.parquet")
        _same(read_parquet(path), dataset)
        assert load_dataset(path).frames == dataset.frames


_finite = st.floats(min_value=-50, max_value=50, allow_nan=False, allow_subnormal=True)
_yaw = st.floats(min_value=-np.pi, max_value=np.pi, allow_nan=False)


@st.composite
def _frames(draw) -> Frame:
    n = draw(st.integers(0, 5))
    ids = draw(st.lists(st.integers(0, 10**12), min_size=n, max_size=n, unique=True))
    position = [[draw(_finite), draw(_finite)] for _ in range(n)]
    yaw = [draw(_yaw) for _ in range(n)]
    kinds = tuple(draw(st.sampled_from(["human", "robot"])) for _ in range(n))
    head_position = head_yaw = None
    if draw(st.booleans()):
        observed = [draw(st.booleans()) for _ in range(n)]
        head_position = [
            [draw(_finite), draw(_finite)] if o else [np.nan, np.nan] for o in observed
        ]
        head_yaw = [draw(_yaw) if o else np.nan for o in observed]
    groups = None
    if draw(st.booleans()):
        shuffled = draw(st.permutations(ids))
        cuts = sorted(draw(st.lists(st.integers(0, n), max_size=3)))
        bounds = [0, *cuts, n]
        groups = tuple(
            tuple(shuffled[a:b]) for a, b in zip(bounds, bounds[1:], strict=False) if b > a
        )
    return Frame(
        ids=np.array(ids, dtype=np.int64),
        position=np.array(position, dtype=np.float64).reshape(n, 2),
        yaw=yaw,
        kinds=kinds,
        head_position=None if head_position is None else np.array(head_position).reshape(n, 2),
        head_yaw=head_yaw,
        groups=groups,
        time=draw(st.floats(0, 1e6, allow_nan=False)),
        sequence=draw(st.sampled_from(["s", "session 2", "épisode"])),
    )


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(frames=st.lists(_frames(), min_size=0, max_size=6))
def test_round_trip_property(tmp_path, frames):
    # A dataset's times increase within each sequence: order the drawn frames so.
    first = {}
    for frame in sorted(frames, key=lambda f: (f.sequence, f.time)):
        first.setdefault((frame.sequence, frame.time), frame)
    frames = list(first.values())
    dataset = Dataset(frames=tuple(frames), name="random", metadata={"n": len(frames)})
    back = read_parquet(write_parquet(dataset, tmp_path / "random.parquet"))
    _same(back, dataset)


def test_shard_folder_reads_in_natural_order(tmp_path):
    root = tmp_path / "runs"
    for episode in (10, 2, 1):
        frame = Frame(
            ids=[episode], position=[[0, 0]], yaw=[0], groups=(), sequence=f"walk/{episode}"
        )
        shard = Dataset(frames=(frame,), name="walk", metadata={"episode": episode})
        write_parquet(shard, root / "scenario=walk" / f"episode={episode}" / "part.parquet")
    (root / "scenario=walk" / ".partial.parquet.tmp").write_text("ignored")
    assert detect_format(root) == "parquet"
    dataset = load_dataset(root)
    assert [f.sequence for f in dataset] == ["walk/1", "walk/2", "walk/10"]
    assert dataset.name == "walk"
    shards = dataset.metadata["shards"]
    assert [s["path"] for s in shards] == [
        "scenario=walk/episode=1/part.parquet",
        "scenario=walk/episode=2/part.parquet",
        "scenario=walk/episode=10/part.parquet",
    ]
    assert shards[2]["metadata"] == {"episode": 10}


def test_shards_may_not_share_a_sequence(tmp_path):
    frame = Frame(ids=[1], position=[[0, 0]], yaw=[0], sequence="same")
    for k in (1, 2):
        write_parquet(
            Dataset(frames=(frame,), name="d"), tmp_path / f"episode={k}" / "part.parquet"
        )
    with pytest.raises(
        DataFormatError,
        match=r"episode=2/part.parquet: field 'sequence': .*episode=1/part.parquet.*found 'same'",
    ):
        read_parquet(tmp_path)


def test_write_is_atomic_and_rejects_non_json_metadata(tmp_path):
    path = tmp_path / "d.parquet"
    write_parquet(_mixed_dataset(), path)
    before = path.read_bytes()
    bad = Dataset(frames=(), name="bad", metadata={"rng": object()})
    with pytest.raises(ValueError, match="metadata must be JSON-serialisable"):
        write_parquet(bad, path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.parquet"]


# --- malformed files ---------------------------------------------------------------------------


def _rewrite(tmp_path: Path, change) -> Path:
    """A valid file, its table passed through ``change(table) -> table``, written back."""
    path = write_parquet(_mixed_dataset(), tmp_path / "good.parquet")
    table = pq.read_table(path)
    bad = change(table)
    out = tmp_path / "bad.parquet"
    pq.write_table(bad, out)
    return out


def _set(table: pa.Table, name: str, row: int, value) -> pa.Table:
    values = table.column(name).to_pylist()
    values[row] = value
    index = table.schema.get_field_index(name)
    return table.set_column(
        index, table.schema.field(name), pa.array(values, type=table.schema.field(name).type)
    )


def test_a_null_where_a_value_is_required_names_its_row(tmp_path):
    def change(table: pa.Table) -> pa.Table:  # a writer that left the column nullable
        values = table.column("frame").to_pylist()
        values[3] = None
        index = table.schema.get_field_index("frame")
        return table.set_column(index, "frame", pa.array(values, type=pa.int64()))

    path = _rewrite(tmp_path, change)
    with pytest.raises(
        DataFormatError, match=r"bad.parquet: row 3: field 'frame': expected a value, found null"
    ):
        read_parquet(path)


def test_missing_column(tmp_path):
    path = _rewrite(tmp_path, lambda t: t.drop_columns(["yaw"]))
    with pytest.raises(DataFormatError, match=r"bad.parquet: field 'yaw': expected a column 'yaw'"):
        read_parquet(path)


def test_a_column_of_another_name_is_refused_not_dropped(tmp_path):
    path = _rewrite(
        tmp_path, lambda t: t.append_column("confidence", pa.array([0.5] * t.num_rows))
    )
    with pytest.raises(
        DataFormatError,
        match=r"bad.parquet: field 'confidence': expected only the columns of format version 1 "
        r"\(sequence, frame, .*\), found a column of another name",
    ):
        read_parquet(path)


def test_wrong_column_type(tmp_path):
    def change(table):
        index = table.schema.get_field_index("x")
        return table.set_column(index, "x", table.column("x").cast(pa.string()))

    with pytest.raises(DataFormatError, match=r"field 'x': expected type double, found string"):
        read_parquet(_rewrite(tmp_path, change))


@pytest.mark.parametrize(
    ("column", "row", "value", "message"),
    [
        pytest.param(
            "x",
            5,
            float("nan"),
            r"bad.parquet: frame 1 \(row 5\): field 'x': expected a finite number, found nan",
            id="nan-position",
        ),
        pytest.param(
            "head_y",
            0,
            float("inf"),
            r"frame 0 \(row 0\): field 'head_y': expected a finite number or NaN, found inf",
            id="inf-head-position",
        ),
        pytest.param(
            "yaw",
            4,
            90.0,
            r"frame 1 \(row 4\): field 'yaw': expected radians in \[-pi, pi\].*degrees.*found 90.0",
            id="yaw-in-degrees",
        ),
        pytest.param(
            "person_id",
            1,
            5,
            r"bad.parquet: frame 0 \(row 1\): field 'person_id'"
            r": expected ids unique within the frame, found 5, already on row 0",
            id="duplicate-ids-in-a-frame",
        ),
        pytest.param(
            "x",
            0,
            None,
            r"frame 0 \(rows 0..3\): field 'x': expected a value on every row",
            id="null-in-a-required-column",
        ),
        pytest.param(
            "group",
            3,
            5,
            r"frame 0 \(rows 0..3\): field 'group': expected indices 0..5, each used",
            id="group-indices-with-a-gap",
        ),
        pytest.param(
            "x",
            4,
            1e200,
            r"frame 1 \(row 4\): field 'x'"
            r": expected metres with \|value\| <= 1e\+08 .*found 1e\+200",
            id="huge-position",
        ),
        pytest.param(
            "head_y",
            0,
            -2e8,
            r"frame 0 \(row 0\): field 'head_y': expected metres .*found -200000000.0",
            id="far-head",
        ),
        pytest.param(
            "head_x",
            0,
            float("nan"),
            r"frame 0 \(row 0\): field 'head_x': expected a number, as head_y and head_yaw "
            r"\(a head is observed in full or not at all\), found nan",
            id="head-partly-nan",
        ),
        pytest.param(
            "head_yaw",
            1,
            0.5,
            r"frame 0 \(row 1\): field 'head_yaw': expected NaN, as head_x and head_y .*found 0.5",
            id="head-partly-observed",
        ),
        pytest.param(
            "time",
            4,
            0.0,
            r"frame 1 \(rows 4..5\): field 'time': expected one value for all rows of the frame",
            id="time-differs-within-a-frame",
        ),
    ],
)
def test_bad_value(tmp_path, column, row, value, message):
    path = _rewrite(tmp_path, lambda t: _set(t, column, row, value))
    with pytest.raises(DataFormatError, match=message):
        read_parquet(path)


def test_group_on_an_unannotated_frame(tmp_path):
    def change(table):
        table = _set(table, "group", 6, 0)
        return _set(table, "group_member", 6, 0)

    with pytest.raises(
        DataFormatError,
        match=r"frame 2 \(rows 6..6\): field 'group': expected null \(the frame is not annotated\)",
    ):
        read_parquet(_rewrite(tmp_path, change))


def test_not_a_reform_file(tmp_path):
    path = tmp_path / "other.parquet"
    pq.write_table(pa.table({"a": [1, 2]}), path)
    with pytest.raises(
        DataFormatError,
        match=r"other.parquet: field 'schema metadata': expected a 'reform_sim' entry",
    ):
        read_parquet(path)


def test_newer_format_version(tmp_path):
    def change(table):
        header = json.loads(table.schema.metadata[METADATA_KEY])
        header["format_version"] = FORMAT_VERSION + 1
        return table.replace_schema_metadata({METADATA_KEY: json.dumps(header).encode()})

    with pytest.raises(
        DataFormatError, match=r"field 'format_version': expected an integer from 1 to 1, found 2"
    ):
        read_parquet(_rewrite(tmp_path, change))


def test_a_changed_bit_in_the_frames_is_found_never_read(tmp_path):
    """Every page is written with its CRC: a bit flipped anywhere before the footer (the
    frames' pages) is refused when read, or changes nothing read (a byte no page holds)."""
    dataset = _mixed_dataset()
    data = write_parquet(dataset, tmp_path / "mixed.parquet").read_bytes()
    footer = int.from_bytes(data[-8:-4], "little") + 8
    refused = 0
    for position in range(4, len(data) - footer, 7):
        changed = bytearray(data)
        changed[position] ^= 1 << (position % 8)
        path = tmp_path / "changed.parquet"
        path.write_bytes(bytes(changed))
        try:
            back = read_parquet(path)
        except DataFormatError as exc:
            assert str(exc).startswith(f"{path}: ")
            refused += 1
            continue
        _same(back, dataset)
    assert refused > 0


def test_empty_corrupt_and_missing(tmp_path):
    (tmp_path / "empty.parquet").write_bytes(b"")
    with pytest.raises(
        DataFormatError, match=r"empty.parquet: expected a Parquet file, found an empty file"
    ):
        read_parquet(tmp_path / "empty.parquet")
    (tmp_path / "junk.parquet").write_bytes(b"\x00\x01 not parquet \xff" * 20)
    with pytest.raises(DataFormatError, match=r"junk.parquet: expected a readable Parquet file"):
        read_parquet(tmp_path / "junk.parquet")
    with pytest.raises(
        DataFormatError,
        match=r"nothing.parquet: expected a Parquet file or a folder of them, found no such file",
    ):
        read_parquet(tmp_path / "nothing.parquet")
    (tmp_path / "folder").mkdir()
    with pytest.raises(
        DataFormatError, match=r"folder: expected a folder holding .parquet files, found none"
    ):
        read_parquet(tmp_path / "folder")


def test_a_git_lfs_pointer_or_a_page_in_place_of_a_parquet_file_is_named(tmp_path):
    """What a clone without Git LFS holds in place of a shard, and a page saved as one."""
    shard = tmp_path / "set" / "episode-0.parquet"
    shard.parent.mkdir()
    shard.write_bytes(b"version https://git-lfs.github.com/spec/v1\noid sha256:00\nsize 9\n")
    lfs = f"{shard}: expected a Parquet file, found a Git LFS pointer, not the file; fetch it "
    for path in (shard, shard.parent):
        with pytest.raises(DataFormatError) as caught:
            read_parquet(path)
        assert str(caught.value) == lfs + "with `git lfs pull`"
    shard.write_bytes(b"<html><body>Moved</body></html>\n")
    with pytest.raises(DataFormatError) as caught:
        read_parquet(shard)
    assert str(caught.value) == (
        f"{shard}: expected a Parquet file, found text starting with '<html><body>Moved</b', "
        "not a Parquet file"
    )


def test_a_compressed_or_damaged_parquet_file_is_said_in_words(tmp_path, salsa_dataset):
    good = tmp_path / "good.parquet"
    write_parquet(salsa_dataset, good)
    packed = tmp_path / "packed.parquet"
    packed.write_bytes(gzip.compress(good.read_bytes()))
    with pytest.raises(DataFormatError) as caught:
        read_parquet(packed)
    assert str(caught.value) == (
        f"{packed}: expected a Parquet file, found a gzip-compressed file; decompress it first"
    )
    cut = tmp_path / "cut.parquet"
    cut.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(DataFormatError) as caught:
        read_parquet(cut)
    message = str(caught.value)
    assert message.startswith(
        f"{cut}: expected a readable Parquet file, found a damaged or cut-short Parquet file ("
    )
    assert "ArrowInvalid" not in message and "OSError" not in message


# --- row order, time order, unfinished folders, codecs ---------------------------------------


@pytest.fixture
def salsa_head(salsa_dataset, tmp_path) -> tuple[Path, Dataset]:
    """SALSA's first three frames (18 people each: rows 0-17, 18-35, 36-53) as Parquet."""
    head = salsa_dataset.subset(salsa_dataset.frames[:3], name="salsa-head")
    return write_parquet(head, tmp_path / "salsa-head.parquet"), head


def _reorder(path: Path, rows: list[int]) -> Path:
    """The file's rows in the order ``rows``, written beside it."""
    out = path.with_name("reordered.parquet")
    pq.write_table(pq.read_table(path).take(rows), out)
    return out


@pytest.mark.parametrize(
    ("swap", "message"),
    [
        pytest.param(
            (0, 20),
            r"reordered.parquet: row 0: field 'frame': expected frame 0 \(rows grouped by frame, "
            r"frames 0, 1, 2, ... in order\), found 1",
            id="rows-0-and-20-swapped",
        ),
        pytest.param(
            (17, 18),
            r"reordered.parquet: row 18: field 'frame': expected frame 1 or 2 .*found 0",
            id="last-row-of-frame-0-after-frame-1-starts",
        ),
        pytest.param(
            (18, 36),
            r"reordered.parquet: row 18: field 'frame': expected frame 0 or 1 .*found 2",
            id="frame-2-row-inside-frame-1",
        ),
    ],
)
def test_rows_not_grouped_by_frame_are_refused(salsa_head, swap, message):
    path, head = salsa_head
    assert read_parquet(path).frames == head.frames
    rows = list(range(54))
    rows[swap[0]], rows[swap[1]] = rows[swap[1]], rows[swap[0]]
    with pytest.raises(DataFormatError, match=message):
        read_parquet(_reorder(path, rows))


@pytest.mark.parametrize(
    ("time", "found"),
    [pytest.param(0.2, "0.2", id="earlier"), pytest.param(3.2, "3.2", id="repeated")],
)
def test_time_must_increase_within_a_sequence(salsa_head, time, found):
    path, head = salsa_head
    assert [f.time for f in head] == [0.2, 3.2, 6.2]
    table = pq.read_table(path)
    times = table.column("time").to_numpy().copy()
    times[36:54] = time  # frame 2 goes back to (or repeats) an earlier time
    bad = table.set_column(
        table.schema.get_field_index("time"), table.schema.field("time"), [times]
    )
    pq.write_table(bad, path.with_name("bad.parquet"))
    with pytest.raises(
        DataFormatError,
        match=r"bad.parquet: frame 2 \(row 36\): field 'time': expected a time > 3.2 \(that of "
        r"the sequence's previous frame, frame 1\): time increases within a sequence, "
        rf"found {found}",
    ):
        read_parquet(path.with_name("bad.parquet"))


def _generated_folder(root: Path, salsa_dataset, *, written: int, episodes: int, complete: bool):
    """A folder shaped as ``reform-sim generate`` writes it: shards and a dataset card."""
    shards = []
    for k in range(written):
        frames = tuple(f.replace(sequence=f"walk-{k}") for f in salsa_dataset.frames[:2])
        path = write_parquet(
            Dataset(frames=frames, name="walk"),
            root / "scenario=walk" / f"episode={k}" / "part.parquet",
        )
        data = path.read_bytes()
        shards.append(
            {
                "path": path.relative_to(root).as_posix(),
                "bytes": len(data),
                "sha256": hashlib.sha256(data).hexdigest(),
            }
        )
    card = {
        "card_version": 1,
        "kind": "reform-sim synthetic dataset",
        "complete": complete,
        "episodes": episodes,
        "command": f"reform-sim generate --scenario walk --episodes {episodes} --seed 0 --out DIR",
        "shards": shards,
    }
    (root / "dataset.json").write_text(json.dumps(card))
    return root


def test_an_unfinished_generated_folder_is_refused(tmp_path, salsa_dataset):
    folder = _generated_folder(
        tmp_path / "data", salsa_dataset, written=7, episodes=30, complete=False
    )
    message = (
        r"data/dataset.json: field 'complete': expected true \(every episode of the run "
        r"written\), found false: incomplete dataset \(7 of 30 episodes written\); run the same "
        r"reform-sim generate command again to finish it \(reform-sim generate --scenario walk "
        rf"--episodes 30 --seed 0 --out {re.escape(str(folder))}\), or pass allow_incomplete=True"
    )
    assert_refused_by_each((read_parquet, load_dataset), folder, message)
    partial = read_parquet(folder, allow_incomplete=True)
    assert partial.sequences() == tuple(f"walk-{k}" for k in range(7))
    assert load_dataset(folder, allow_incomplete=True).frames == partial.frames
    # One shard of it is an ordinary file.
    assert len(read_parquet(folder / "scenario=walk" / "episode=0" / "part.parquet")) == 2


def test_a_finished_generated_folder_reads(tmp_path, salsa_dataset):
    folder = _generated_folder(
        tmp_path / "data", salsa_dataset, written=3, episodes=3, complete=True
    )
    assert read_parquet(folder).sequences() == ("walk-0", "walk-1", "walk-2")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"shards": None}, r"field 'shards': expected the list of the dataset's shards, found"),
        ({"complete": "yes"}, r"field 'complete': expected true or false, found 'yes'"),
        (
            {"shards": [{"path": "scenario=walk/episode=0/part.parquet", "bytes": "many"}]},
            r"shards\[0\]: field 'bytes': expected a size in bytes, found 'many'",
        ),
        (
            {"shards": [{"path": "scenario=walk/episode=0/part.parquet", "sha256": 12}]},
            r"shards\[0\]: field 'sha256': expected a sha256 hex digest, found 12",
        ),
        (
            {"shards": [{"path": "scenario=walk/episode=0/part.parquet"}] * 2, "episodes": 2},
            r"shards\[1\]: field 'path': expected each shard listed once",
        ),
        ({"episodes": 5}, r"field 'episodes': expected the number of shards the card lists \(1\)"),
        ({"card_version": 99}, r"field 'card_version': expected an integer from 1 to 1"),
        (
            {"shards": [{"path": "../../etc/passwd"}]},
            r"expected a path inside the dataset's folder",
        ),
    ],
    ids=[
        "no-shard-list",
        "complete-not-a-bool",
        "bytes-not-a-number",
        "sha-not-text",
        "twice",
        "episodes-disagree",
        "newer-card",
        "outside-the-folder",
    ],
)
def test_a_card_that_cannot_vouch_for_its_shards_is_refused(
    tmp_path, salsa_dataset, change, message
):
    folder = _generated_folder(
        tmp_path / "data", salsa_dataset, written=1, episodes=1, complete=True
    )
    card = json.loads((folder / "dataset.json").read_text()) | change
    (folder / "dataset.json").write_text(json.dumps(card))
    with pytest.raises(DataFormatError, match=message):
        read_parquet(folder)


def test_a_card_nested_too_deep_or_not_a_file_is_one_error(tmp_path, salsa_dataset):
    folder = _generated_folder(
        tmp_path / "data", salsa_dataset, written=1, episodes=1, complete=True
    )
    (folder / "dataset.json").write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(DataFormatError, match=r"found JSON nested too deep to read"):
        read_parquet(folder)
    (folder / "dataset.json").unlink()
    (folder / "dataset.json").mkdir()
    with pytest.raises(DataFormatError, match=r"dataset card \(a JSON file\), found a folder"):
        read_parquet(folder)


def test_a_corrupt_card_is_named(tmp_path, salsa_dataset):
    folder = _generated_folder(
        tmp_path / "data", salsa_dataset, written=1, episodes=1, complete=True
    )
    (folder / "dataset.json").write_text('{"complete": fal')
    with pytest.raises(
        DataFormatError, match=r"dataset.json: expected a reform-sim dataset card \(JSON\)"
    ):
        read_parquet(folder)


def test_unknown_compression_is_refused_before_writing(tmp_path):
    with pytest.raises(
        ValueError,
        match=r"compression must be one of \('none', 'snappy', 'gzip', 'brotli', 'lz4', 'zstd'\)"
        r", got 'bogus'",
    ):
        write_parquet(_mixed_dataset(), tmp_path / "d.parquet", compression="bogus")
    assert list(tmp_path.iterdir()) == []
    for codec in ("none", "snappy", "ZSTD"):
        path = write_parquet(_mixed_dataset(), tmp_path / f"{codec}.parquet", compression=codec)
        _same(read_parquet(path), _mixed_dataset())


@pytest.mark.parametrize(
    ("header", "message"),
    [
        (b"[1, 2]", r"field 'schema metadata': expected a JSON object, found a JSON list"),
        (
            b'{"format_version": 1, "name": {"a": 1}}',
            r"field 'name': expected a JSON string, found dict",
        ),
        (
            b'{"format_version": 1, "metadata": [1]}',
            r"field 'metadata': expected a JSON object, found list",
        ),
        (b"[" * 100_000 + b"]" * 100_000, r"expected a JSON object, found JSON nested too deep"),
    ],
    ids=["a-list", "name-an-object", "metadata-a-list", "too-deep"],
)
def test_a_header_of_the_wrong_shape_is_one_error(tmp_path, header, message):
    import pyarrow.parquet as pq

    path = write_parquet(_mixed_dataset(), tmp_path / "good.parquet")
    table = pq.read_table(path)
    bad = table.replace_schema_metadata({**table.schema.metadata, METADATA_KEY: header})
    pq.write_table(bad, tmp_path / "bad.parquet")
    with pytest.raises(DataFormatError, match=message):
        read_parquet(tmp_path / "bad.parquet")


def test_a_file_whose_rows_cannot_fit_memory_is_refused_before_it_is_read(tmp_path, monkeypatch):
    path = write_parquet(_mixed_dataset(), tmp_path / "d.parquet")
    # A machine with far less memory than the file's rows need (a few MB of Parquet can claim a
    # hundred million rows): refused from the footer's row count, nothing read.
    monkeypatch.setattr(_parquet_read, "READ_BYTES_PER_ROW", 2**50)
    with pytest.raises(DataFormatError, match=r"d.parquet: expected a file whose rows fit the"):
        read_parquet(path)


def test_negative_person_ids_are_refused_and_never_written(tmp_path):
    path = _rewrite(tmp_path, lambda t: _set(t, "person_id", 1, -5))
    with pytest.raises(DataFormatError) as caught:
        read_parquet(path)
    assert str(caught.value) == (
        f"{path}: frame 0 (row 1): field 'person_id': expected an id >= 0 (person ids are never "
        "negative), found -5"
    )
    frame = Frame(ids=[3, -1], position=[[0.0, 0.0], [1.0, 0.0]], yaw=[0.0, 3.0])
    out = tmp_path / "negative.parquet"
    with pytest.raises(ValueError, match=r"person ids must be >= 0 .*got -1 in frame 0"):
        write_parquet(Dataset(frames=(frame,), name="n"), out)
    assert not out.exists()

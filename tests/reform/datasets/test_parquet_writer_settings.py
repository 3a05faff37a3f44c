"""How the Parquet writer lays a file out: a dictionary for the columns whose values repeat, the
float columns plain; and a file laid out as earlier ones were (every column in a dictionary,
pyarrow's default) still reads as the same dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from reform import Dataset, Frame
from reform.datasets.parquet import COLUMNS, read_parquet, write_parquet

_FLOATS = {name for name, spec in COLUMNS.items() if spec[0] == "float64"}
_FLAGS = {name for name, spec in COLUMNS.items() if spec[0] == "bool"}  # bits, never a dictionary


def _dataset() -> Dataset:
    """Frames with heads (one unobserved), without heads, an empty frame, groups and none."""
    rng = np.random.default_rng(7)
    frames = []
    for k in range(40):
        n = 0 if k == 5 else 6
        heads = k % 3 != 0
        head_position = rng.uniform(-5.0, 5.0, (n, 2)) if heads else None
        if heads and n:
            head_position[1] = np.nan
        frames.append(
            Frame(
                ids=np.arange(n) + 10,
                position=rng.uniform(-5.0, 5.0, (n, 2)),
                yaw=rng.uniform(-np.pi, np.pi, n),
                head_position=head_position,
                head_yaw=(
                    np.where(np.isnan(head_position[:, 0]), np.nan, rng.uniform(-3, 3, n))
                    if heads
                    else None
                ),
                groups=None if k % 4 == 3 else (((10, 11, 12), (14, 13)) if n else ()),
                time=0.5 * k,
                sequence="episode-0",
            )
        )
    return Dataset(frames=tuple(frames), name="settings", source="hand-made", metadata={"k": 1})


def _dictionary_columns(path: Path) -> set[str]:
    """The columns of ``path`` with a dictionary page in every row group."""
    metadata = pq.ParquetFile(path).metadata
    schema = metadata.schema
    return {
        schema.column(i).name
        for i in range(metadata.num_columns)
        if all(
            metadata.row_group(g).column(i).has_dictionary_page
            for g in range(metadata.num_row_groups)
        )
    }


@pytest.fixture
def written(tmp_path: Path) -> Path:
    return write_parquet(_dataset(), tmp_path / "new.parquet")


def test_only_the_columns_whose_values_repeat_have_a_dictionary(written):
    assert _dictionary_columns(written) == set(COLUMNS) - _FLOATS - _FLAGS
    assert _FLOATS == {"time", "x", "y", "yaw", "head_x", "head_y", "head_yaw"}


def test_a_file_with_every_column_in_a_dictionary_reads_as_the_same_dataset(written, tmp_path):
    earlier = tmp_path / "earlier.parquet"
    pq.write_table(pq.read_table(written), earlier, compression="zstd")  # pyarrow's defaults
    assert _dictionary_columns(earlier) == set(COLUMNS) - _FLAGS
    new, old = read_parquet(written), read_parquet(earlier)
    assert new.frames == old.frames == _dataset().frames
    assert (new.name, new.source, dict(new.metadata)) == (old.name, old.source, {"k": 1})


def test_the_same_dataset_writes_the_same_bytes(written, tmp_path):
    again = write_parquet(_dataset(), tmp_path / "again.parquet")
    assert again.read_bytes() == written.read_bytes()

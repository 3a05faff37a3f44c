"""A shard damaged as a disk or a careless hand damages it: one float changed, the file the same
size, its footer intact (it still reads, with a wrong value): for the resume and verify tests."""

from __future__ import annotations

import io

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

COLUMN = "x"  # the float column whose value is changed (metres)


def one_float_changed(content: bytes) -> bytes:
    """``content`` (a Parquet shard) with one value of column ``x`` changed in its last bit,
    written again as the shard was (zstd, the same columns with a dictionary, each page's CRC
    made again), of the same size:
    the first row for which the compressed file keeps its length.

    Raises:
        AssertionError: no row gives a file of the same size.
    """
    table = pq.read_table(io.BytesIO(content))
    column = table.column(COLUMN).to_numpy(zero_copy_only=False)
    nulls = table.column(COLUMN).is_null().to_numpy(zero_copy_only=False)
    index = table.schema.get_field_index(COLUMN)
    metadata = pq.ParquetFile(io.BytesIO(content)).metadata
    dictionary = [
        metadata.schema.column(i).name
        for i in range(metadata.num_columns)
        if metadata.row_group(0).column(i).has_dictionary_page
    ]
    for row in range(1, len(column) - 1):
        if nulls[row] or not np.isfinite(column[row]):
            continue
        values = column.copy()
        values[row] = np.nextafter(values[row], np.inf)
        changed = table.set_column(
            index, table.schema.field(index), pa.array(values, type=pa.float64(), mask=nulls)
        )
        out = io.BytesIO()
        pq.write_table(
            changed, out, compression="zstd", use_dictionary=dictionary, write_page_checksum=True
        )
        damaged = out.getvalue()
        if len(damaged) == len(content) and damaged != content:
            return damaged
    raise AssertionError("no one-float change keeps the shard's size")

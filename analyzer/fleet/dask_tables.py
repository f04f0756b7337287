"""``fleet --dask``: the tables read and cut down by dask.dataframe on a cluster's workers.

The workers read the Parquet files (they must reach the dataset by the same path), keep
only the columns and rows the questions need, and send back that much; DuckDB then
answers here exactly as it does from the files.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import TYPE_CHECKING

import pyarrow as pa
import pyarrow.parquet as pq

from analyzer.errors import UsageError
from analyzer.fleet.columns import RECORDINGS, TABLES
from analyzer.fleet.dataset import Dataset
from analyzer.fleet.runner import connect

if TYPE_CHECKING:
    import pandas as pd

# The columns of each table the standard questions read (None: every column).
QUESTION_COLUMNS: dict[str, list[str] | None] = {
    RECORDINGS: None,
    "findings": ["recording", "content_hash", "time", "command", "verdict", "response_s"],
}


def read_part(path: str, columns: Sequence[str], schema: pa.Schema) -> pd.DataFrame:
    """One Parquet file as a frame with every column of ``schema`` (null where absent)."""
    import pandas as pd

    table = pq.read_table(path, columns=[c for c in columns if c in pq.read_schema(path).names])
    for field in schema:
        if field.name not in table.column_names:
            table = table.append_column(field, pa.nulls(table.num_rows, field.type))
    frame: pd.DataFrame = table.select(list(columns)).to_pandas(types_mapper=pd.ArrowDtype)
    return frame


def tables_named(sql: str) -> dict[str, list[str] | None]:
    """The tables a query names (whole), for ``fleet --sql ... --dask``."""
    words = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", sql.lower()))
    return {name: None for name in TABLES if name in words}


def dask_tables(
    root: str, address: str, wanted: dict[str, list[str] | None] | None = None
) -> dict[str, pa.Table]:
    """The tables ``wanted`` (name -> columns, None for all; default: what the standard
    questions read), read and cut down on the cluster's workers."""
    import dask.dataframe as dd

    dataset = Dataset(root)
    if not dataset.hashes():
        raise UsageError(f"{root} holds no fleet dataset (make one with `gimbal-analyzer table`)")
    wanted = QUESTION_COLUMNS if wanted is None else wanted
    client = connect(address)
    out: dict[str, pa.Table] = {}
    try:
        for name, columns in wanted.items():
            files = [str(p) for p in dataset.files(name)]
            if not files:
                continue
            schema = pa.unify_schemas([pq.read_schema(f) for f in files])
            names = list(columns) if columns is not None else schema.names
            schema = pa.schema([schema.field(n) for n in names])
            meta = read_meta(schema)
            frame = dd.from_map(read_part, files, columns=names, schema=schema, meta=meta)
            computed = client.compute(frame).result()
            out[name] = pa.Table.from_pandas(computed, schema=schema, preserve_index=False)
    finally:
        client.close()
    return out


def read_meta(schema: pa.Schema) -> pd.DataFrame:
    import pandas as pd

    empty: pd.DataFrame = schema.empty_table().to_pandas(types_mapper=pd.ArrowDtype)
    return empty

"""The dataset's tables as dask.dataframe frames read on a cluster's workers (``--dask``).

The workers read the Parquet files themselves (they must reach the dataset by the same
path), only the columns asked for. ``fleet --dask --sql`` brings the columns a query names
back here, where DuckDB runs the query: SQL in general cannot be cut into worker tasks.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from typing import TYPE_CHECKING

import pyarrow as pa
import pyarrow.parquet as pq

from analyzer.errors import UsageError
from analyzer.fleet.columns import TABLES
from analyzer.fleet.dataset import Dataset
from analyzer.fleet.runner import cluster_error

PART_BYTES = 64 << 20  # Parquet bytes read into one partition (one task)

if TYPE_CHECKING:
    import dask.dataframe as dd
    import pandas as pd
    from distributed import Client


def read_part(paths: Sequence[str], columns: Sequence[str], schema: pa.Schema) -> pd.DataFrame:
    """Parquet files as one frame with every column of ``schema`` (null where absent)."""
    import pandas as pd

    parts = []
    for path in paths:
        table = pq.read_table(path, columns=[c for c in columns if c in pq.read_schema(path).names])
        for field in schema:
            if field.name not in table.column_names:
                table = table.append_column(field, pa.nulls(table.num_rows, field.type))
        parts.append(table.select(list(columns)).cast(schema))
    whole = pa.concat_tables(parts) if parts else schema.empty_table()
    frame: pd.DataFrame = whole.to_pandas(types_mapper=pd.ArrowDtype)
    return frame


def partitions(files: Sequence[str], spread: int) -> list[list[str]]:
    """The files in groups of about PART_BYTES (a partition each), at least ``spread``
    groups when there are that many files, so every worker gets some."""
    sizes = [os.path.getsize(f) for f in files]
    count = max(min(len(files), spread), -(-sum(sizes) // PART_BYTES), 1)
    per = -(-len(files) // count)
    return [list(files[i : i + per]) for i in range(0, len(files), per)]


def read_meta(schema: pa.Schema) -> pd.DataFrame:
    import pandas as pd

    empty: pd.DataFrame = schema.empty_table().to_pandas(types_mapper=pd.ArrowDtype)
    return empty


def table_schema(dataset: Dataset, name: str) -> pa.Schema | None:
    """The columns of a table over all its files (None when it has no files)."""
    files = dataset.files(name)
    if not files:
        return None
    return pa.unify_schemas([pq.read_schema(f) for f in files])


def table_frame(
    dataset: Dataset,
    name: str,
    columns: Sequence[str] | None,
    schema: pa.Schema,
    spread: int = 1,
) -> dd.DataFrame:
    """A lazy frame of one table read on the workers, a partition per group of files."""
    import dask.dataframe as dd

    names = [n for n in (columns if columns is not None else schema.names) if n in schema.names]
    picked = pa.schema([schema.field(n) for n in names])
    groups = partitions([str(p) for p in dataset.files(name)], spread)
    return dd.from_map(read_part, groups, columns=names, schema=picked, meta=read_meta(picked))


def tables_named(sql: str) -> dict[str, set[str] | None]:
    """The tables a query names, each with the words of the query (its possible columns),
    or None (every column) when the query may take columns it does not name."""
    lowered = sql.lower()
    words = set(re.findall(r"[a-z_][a-z0-9_]*", lowered))
    every = "*" in lowered.replace("count(*)", "") or bool(words & {"natural", "columns"})
    return {name: (None if every else words) for name in TABLES if name in words}


def workers(client: Client) -> int:
    """How many partitions spread a small table over the cluster: twice its workers."""
    return 2 * max(1, len(client.scheduler_info().get("workers", {})))


def dask_tables(
    root: str, client: Client, wanted: dict[str, set[str] | None]
) -> dict[str, pa.Table]:
    """The tables ``wanted`` (name -> words naming columns, None for all), read on the
    cluster's workers with only those columns, brought here."""
    dataset = Dataset(root)
    if not dataset.hashes():
        raise UsageError(f"{root} holds no fleet dataset (make one with `gimbal-analyzer table`)")
    out: dict[str, pa.Table] = {}
    for name, words in wanted.items():
        schema = table_schema(dataset, name)
        if schema is None:
            continue
        columns = None if words is None else [n for n in schema.names if n.lower() in words]
        frame = table_frame(dataset, name, columns, schema, workers(client))
        try:
            computed = client.compute(frame).result()
        except Exception as exc:  # a task's failure, or a cluster without the package
            raise cluster_error(client, exc) from None
        picked = pa.schema([schema.field(n) for n in frame.columns])
        out[name] = pa.Table.from_pandas(computed, schema=picked, preserve_index=False)
    return out

"""The fleet: many recordings as one Parquet dataset, asked with DuckDB or Dask."""

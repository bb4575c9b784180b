"""The batch's one results table: one row per item x segment (a failed item: one row with its error).

Written to ``DIR/results.csv`` and ``DIR/results.parquet`` (pyarrow) as items finish: the CSV is
appended and flushed per item (readable at any moment); the Parquet file gets one row group per item and
is complete when the batch ends or is interrupted (Parquet's footer is written last). Every run first
rewrites both from the journal's retained records, so a hard-killed client loses no row.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from types import TracebackType
from typing import IO, Any, Self

import pyarrow as pa

#: Column -> Arrow type, in table order (the one definition of the table's columns).
COLUMNS: dict[str, pa.DataType] = {
    "item": pa.string(),
    "kind": pa.string(),
    "input": pa.string(),
    "status": pa.string(),
    "segment": pa.string(),
    "volume_l": pa.float64(),
    "mass_kg": pa.float64(),
    "rms_mesh_to_points_mm": pa.float64(),
    "rms_points_to_mesh_mm": pa.float64(),
    "iterations": pa.int64(),
    "cloud_points": pa.int64(),
    "warnings": pa.string(),
    "error_type": pa.string(),
    "error": pa.string(),
    "seconds": pa.float64(),
    "attempts": pa.int64(),
    "worker": pa.string(),
    "input_hash": pa.string(),
    "params_key": pa.string(),
    "finished_utc": pa.string(),
}
SCHEMA = pa.schema(list(COLUMNS.items()))
#: The table files in the output folder.
CSV_NAME = "results.csv"
PARQUET_NAME = "results.parquet"

_ITEM_FIELDS = ("item", "kind", "input", "status", "error_type", "error", "seconds", "attempts", "worker",
                "input_hash", "params_key", "finished_utc", "rms_mesh_to_points_mm", "rms_points_to_mesh_mm",
                "iterations", "cloud_points", "warnings")


def rows_of(record: dict[str, Any]) -> list[dict[str, Any]]:
    """The table rows of one journal record: one per segment and aggregate of ``volumes_l`` (with the
    segment's mass at the record's density), or one row without a segment for a failed item."""
    base = {k: record.get(k) for k in _ITEM_FIELDS}
    vols: dict[str, float] = record.get("volumes_l") or {}
    density = float(record.get("density_kg_m3") or 1000.0)
    if record.get("status") != "ok" or not vols:
        return [{**base, "segment": None, "volume_l": None, "mass_kg": None}]
    return [{**base, "segment": seg, "volume_l": float(v), "mass_kg": float(v) * density / 1000.0}
            for seg, v in vols.items()]


def _batch(rows: list[dict[str, Any]]) -> pa.RecordBatch:
    return pa.RecordBatch.from_pylist(rows, schema=SCHEMA)


class ResultsTable:
    """The open results table of one run (a context manager): :meth:`add` appends an item's rows."""

    def __init__(self, out_dir: Path, records: Iterable[dict[str, Any]] = ()) -> None:
        import pyarrow.csv as pcsv
        import pyarrow.parquet as pq

        self.out_dir = out_dir
        self.csv_path = out_dir / CSV_NAME
        self.parquet_path = out_dir / PARQUET_NAME
        self._csv_tmp = out_dir / f".{CSV_NAME}.partial"
        self._parquet_tmp = out_dir / f".{PARQUET_NAME}.partial"
        self._csv_fh: IO[bytes] = self._csv_tmp.open("wb")
        self._csv = pcsv.CSVWriter(self._csv_fh, SCHEMA)
        self._parquet = pq.ParquetWriter(self._parquet_tmp, SCHEMA)
        self.rows = 0
        for rec in records:
            self.add(rec, flush=False)
        self._csv_fh.flush()
        os.replace(self._csv_tmp, self.csv_path)  # the old table goes only once the new one holds its rows

    def add(self, record: dict[str, Any], flush: bool = True) -> None:
        """Appends the rows of one journal record to both files."""
        batch = _batch(rows_of(record))
        self._csv.write_batch(batch)
        self._parquet.write_batch(batch)
        self.rows += batch.num_rows
        if flush:
            self._csv_fh.flush()

    def close(self) -> None:
        """Completes the Parquet file and renames it into place."""
        self._csv.close()
        self._csv_fh.close()
        self._parquet.close()
        os.replace(self._parquet_tmp, self.parquet_path)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


def read_table(out_dir: Path) -> pa.Table:
    """The results table of a batch folder (its Parquet file)."""
    import pyarrow.parquet as pq

    return pq.read_table(out_dir / PARQUET_NAME)


__all__ = ["COLUMNS", "CSV_NAME", "PARQUET_NAME", "SCHEMA", "ResultsTable", "read_table", "rows_of"]

"""``bsv batch``: a study's captures or clouds processed on Dask distributed, resumable, one results table.

Modules: :mod:`~bsv.batch.items` (inputs, manifests, names, input hashes), :mod:`~bsv.batch.state`
(parameters key, the journal that makes a batch resumable), :mod:`~bsv.batch.task` (one item on a
worker, written atomically), :mod:`~bsv.batch.table` (the Parquet + CSV results table),
:mod:`~bsv.batch.cluster` (LocalCluster or a running scheduler), :mod:`~bsv.batch.runner` (submit,
collect, timeouts), :mod:`~bsv.batch.main` (the command line), :mod:`~bsv.batch.bench` (scaling numbers).
Needs ``pip install 'bsv[batch]'`` (dask[distributed], pyarrow, bokeh for the dashboard).
"""

from __future__ import annotations

from typing import Any

_EXPORTS = {"Item": "items", "collect_items": "items", "BatchResult": "runner", "run_batch": "runner", "Spec": "state"}


def __getattr__(name: str) -> Any:
    """The public names, imported on first use (``import bsv.batch`` needs neither Dask nor pyarrow)."""
    import importlib

    if name in _EXPORTS:
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module 'bsv.batch' has no attribute {name!r}")


__all__ = ["BatchResult", "Item", "Spec", "collect_items", "run_batch"]

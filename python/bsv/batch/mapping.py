"""One function over many arguments on the batch's Dask cluster, results as they finish (``bsv bench``).

The benchmarks (``bsv bench synth|faust --scheduler``) send their subjects through the same cluster as
``bsv batch`` (:func:`bsv.batch.cluster.open_client`: a LocalCluster of one-thread workers, or a running
scheduler). They write their own tables, so this is only the submit-and-collect part: a task that raises
(or whose workers keep dying) is yielded as its exception, and the caller records it.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator, Sequence
from typing import Any, TypeVar

from .cluster import LOCAL, dashboard_text, open_client

A = TypeVar("A")


def map_unordered(fn: Callable[[A], Any], args: Sequence[A], *, scheduler: str | None = None, workers: int = 2,
                  announce: bool = True) -> Iterator[tuple[int, Any]]:
    """``fn(arg)`` for every argument as one Dask task each; yields ``(index, result)`` in completion
    order, the result being the task's exception when it failed. ``scheduler``: ``None``/``"local"`` (a
    LocalCluster of ``workers`` processes) or a scheduler address; ``announce`` prints the dashboard
    line to stderr."""
    from distributed import as_completed

    with open_client(scheduler or LOCAL, workers) as client:
        if announce:
            print(dashboard_text(client), file=sys.stderr, flush=True)
        futures = [client.submit(fn, a, pure=False) for a in args]
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            i = index[fut.key]
            if fut.status == "finished":
                yield i, fut.result()
            else:
                exc = fut.exception()
                yield i, exc if exc is not None else RuntimeError(f"task {i} was {fut.status}")


__all__ = ["map_unordered"]

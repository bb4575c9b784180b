"""The Dask cluster of a batch: an embedded ``LocalCluster`` or any running scheduler (``tcp://...``).

Local: ``workers`` worker processes with one thread each (the Rust core runs its own threads inside a
task; two Python threads per worker would only make them compete), each under a nanny that restarts it
when it dies. A worker that dies mid-task (killed, out of memory) makes the scheduler run its task on
another worker, up to ``allowed_failures`` times (``distributed.scheduler.allowed-failures``), then the
task fails with ``KilledWorker`` and the batch records it. A remote scheduler (Slurm through
dask-jobqueue, Kubernetes through dask-kubernetes) uses its own configuration for that.

The dashboard needs bokeh; without it the cluster runs without one and :func:`dashboard_text` says how
to turn it on.
"""

from __future__ import annotations

import contextlib
import importlib.util
from collections.abc import Iterator
from typing import Any

from ..errors import BatchInputError

#: ``--scheduler`` value of the embedded LocalCluster.
LOCAL = "local"
#: What to install for the dashboard.
DASHBOARD_HINT = "pip install bokeh (or pip install 'bsv[batch]')"


def has_dashboard() -> bool:
    """Whether the Dask dashboard can run (bokeh installed)."""
    return importlib.util.find_spec("bokeh") is not None


def dashboard_text(client: Any) -> str:
    """One line for the user: the dashboard's address, or that it is off and how to turn it on."""
    link = getattr(client, "dashboard_link", None) if has_dashboard() else None
    if link:
        return f"Dask dashboard: {link}"
    return f"Dask dashboard: off (it needs bokeh: {DASHBOARD_HINT})"


def check_scheduler(scheduler: str, workers: int) -> None:
    """Refuses a ``--scheduler`` that is neither ``local`` nor an address, and ``--workers`` below 1
    (:class:`bsv.errors.BatchInputError`), before anything is written."""
    if scheduler == LOCAL:
        if workers < 1:
            raise BatchInputError(f"--workers {workers}: need at least one worker")
    elif "://" not in scheduler:
        raise BatchInputError(f"--scheduler {scheduler!r}: use 'local' or a scheduler address such as "
                              "tcp://host:8786")


@contextlib.contextmanager
def open_client(scheduler: str = LOCAL, workers: int = 2, *, allowed_failures: int = 3,
                dashboard: bool = True) -> Iterator[Any]:
    """A connected ``dask.distributed.Client``: to a new LocalCluster of ``workers`` one-thread worker
    processes (``scheduler="local"``), or to the running scheduler at ``scheduler`` (``tcp://host:8786``,
    ``tls://...``). The local cluster is shut down on exit; a remote one is left running."""
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise BatchInputError(f"bsv batch needs Dask distributed ({exc}): pip install 'bsv[batch]' "
                              "(dask[distributed], pyarrow, bokeh)") from exc
    check_scheduler(scheduler, workers)
    if scheduler == LOCAL:
        with dask.config.set({"distributed.scheduler.allowed-failures": int(allowed_failures)}):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=":8787" if dashboard and has_dashboard() else None)
        try:
            with Client(cluster) as client:
                yield client
        finally:
            cluster.close()
        return
    try:
        client = Client(scheduler, timeout="30s")
    except OSError as exc:
        raise BatchInputError(f"--scheduler {scheduler}: cannot connect ({exc}); is the scheduler running "
                              "and reachable from here?") from exc
    try:
        yield client
    finally:
        client.close()


__all__ = ["DASHBOARD_HINT", "LOCAL", "check_scheduler", "dashboard_text", "has_dashboard", "open_client"]

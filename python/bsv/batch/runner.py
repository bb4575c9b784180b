"""The batch runner: plan (what is already done), submit one Dask task per item, collect as they finish.

- Plan: every item's input hash (read where the client runs; threads) against the journal
  (:mod:`bsv.batch.state`); current items are skipped and keep their recorded rows.
- Run: one ``client.submit`` per remaining item (``retries`` for unexpected exceptions; a dead worker's
  task is re-run elsewhere by the scheduler), collected with ``dask.distributed.as_completed`` under a
  tqdm bar (rate and ETA); each finished item goes at once to the journal and the table.
- Timeout: each task logs an event when it starts on a worker; a task still running ``timeout`` seconds
  later is cancelled and its worker restarted (a running Python/Rust computation cannot be stopped from
  outside its process), and the item is recorded as failed (``TimeoutError``).
- Failure isolation: nothing an item does stops the batch; exit status 1 when any item of the batch
  failed (this run or a recorded failure that was skipped), 0 when all are done.
"""

from __future__ import annotations

import contextlib
import json
import shutil
import signal
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ..errors import OutputExistsError
from ..exitcodes import EXIT_FAILED, EXIT_OK
from .cluster import LOCAL, check_scheduler, dashboard_text, open_client
from .items import Item, input_hash
from .state import JOURNAL, Journal, Spec, is_current, load_journal
from .table import CSV_NAME, PARQUET_NAME, ResultsTable
from .task import ITEM_JSON, START_TOPIC, run_item


@dataclass
class BatchResult:
    """What a batch run did: records of every item of the batch (new and skipped), counts, wall time."""

    out_dir: Path
    records: dict[str, dict[str, Any]]
    ran: int
    skipped: int
    wall_s: float
    dashboard: str = ""
    #: Start events per item this run (> 1: the task was re-run after its worker died).
    attempts: dict[str, int] = field(default_factory=dict)

    @property
    def failed(self) -> list[str]:
        """Names of the items whose (last) record is a failure."""
        return sorted(k for k, r in self.records.items() if r.get("status") != "ok")

    @property
    def done(self) -> list[str]:
        """Names of the items whose (last) record is a success."""
        return sorted(k for k, r in self.records.items() if r.get("status") == "ok")

    @property
    def exit_code(self) -> int:
        """1 when any item failed, else 0 (:mod:`bsv.exitcodes`)."""
        return EXIT_FAILED if self.failed else EXIT_OK


def check_out_dir(out: Path) -> None:
    """The output folder is new, empty, or a batch folder (it holds the journal); anything else is refused
    (:class:`bsv.errors.OutputExistsError`), so a batch never writes into a folder of other files."""
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{out} exists and is not a folder; choose another --out")
    if out.is_dir() and not (out / JOURNAL).is_file() and any(out.iterdir()):
        raise OutputExistsError(f"{out} holds files but is not a batch folder (no {JOURNAL}); choose a new or "
                                "empty --out, or the folder of the batch to continue")


def _hashes(items: Sequence[Item], progress: bool) -> list[str]:
    from tqdm import tqdm

    with ThreadPoolExecutor(max_workers=4) as pool:
        return list(tqdm(pool.map(input_hash, items), total=len(items), desc="hashing inputs", unit="item",
                         disable=not progress or len(items) < 50))


def _now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _remove_leftovers(out: Path) -> None:
    """Temporary item folders of tasks killed in an earlier run (a live task's folder is never removed:
    this runs only when no task of this batch is running)."""
    for p in [*out.glob(".tmp-*"), *out.glob(".old-*")]:
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)


class _Starts:
    """Task start events (from the workers, through the scheduler): when and where each item started."""

    def __init__(self, on_start: Callable[[dict[str, Any]], None] | None) -> None:
        self.lock = threading.Lock()
        self.started: dict[str, tuple[float, str]] = {}
        self.attempts: dict[str, int] = {}
        self.on_start = on_start

    def __call__(self, event: Any) -> None:
        msg = event[1] if isinstance(event, tuple) else event
        if not isinstance(msg, dict) or "item" not in msg:
            return
        with self.lock:
            self.started[msg["item"]] = (time.monotonic(), str(msg.get("worker", "")))
            self.attempts[msg["item"]] = self.attempts.get(msg["item"], 0) + 1
        if self.on_start is not None:
            self.on_start(msg)


def _watchdog(client: Any, futures: dict[str, Any], starts: _Starts, timeout: float, timed_out: dict[str, str],
              stop: threading.Event) -> None:
    """Cancels every task running longer than ``timeout`` and restarts its worker."""
    while not stop.wait(min(0.25, timeout / 4)):
        now = time.monotonic()
        with starts.lock:
            late = [(n, w) for n, (t, w) in starts.started.items()
                    if now - t > timeout and n not in timed_out and not futures[n].done()]
        for name, worker in late:
            timed_out[name] = worker
            futures[name].cancel()
            with contextlib.suppress(Exception):
                client.restart_workers([worker], raise_for_error=False)


@contextlib.contextmanager
def _deferred_interrupt() -> Iterator[None]:
    """A Ctrl-C (SIGINT) arriving during the block is raised right after it, not inside it (main thread
    only; a signal mask would not do: the kernel hands a process-directed signal to any thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: received.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if received:
        raise KeyboardInterrupt


def _placed(out: Path, name: str, input_hash: str, key: str) -> dict[str, Any] | None:
    """The record of an item whose task completed its folder but died before returning (a worker killed
    or restarted in that instant): its ``item.json`` for these inputs and parameters, else None."""
    try:
        rec = json.loads((out / name / ITEM_JSON).read_text())
    except (OSError, ValueError):
        return None
    ok = isinstance(rec, dict) and rec.get("status") == "ok"
    return rec if ok and rec.get("input_hash") == input_hash and rec.get("params_key") == key else None


def _remove_stale(out: Path, name: str) -> None:
    """A failed item has no folder: the folder of an earlier result (other inputs or parameters, no longer
    the item's record) goes (DIR/<item>/ exists exactly when the item's current record is a success)."""
    folder = out / name
    if folder.is_dir():
        shutil.rmtree(folder, ignore_errors=True)


def _failure(name: str, item: Item, fut: Any, timed_out: dict[str, str], timeout: float | None) -> dict[str, Any]:
    if name in timed_out:
        return {"status": "failed", "error_type": "TimeoutError",
                "error": f"ran past --timeout {timeout:g} s on {timed_out[name]}; cancelled (the worker was restarted)"}
    if fut.status == "cancelled":
        return {"status": "failed", "error_type": "CancelledError", "error": "the task was cancelled"}
    exc = fut.exception()
    if type(exc).__name__ == "KilledWorker":
        return {"status": "failed", "error_type": "KilledWorker",
                "error": f"every worker that ran {item.path} died (crash, out of memory, killed): {exc}"}
    return {"status": "failed", "error_type": type(exc).__name__, "error": str(exc)}


def run_batch(
    items: Sequence[Item],
    out_dir: str | Path,
    spec: Spec | None = None,
    *,
    scheduler: str = LOCAL,
    workers: int = 2,
    client: Any = None,
    timeout: float | None = None,
    retries: int = 1,
    rerun_failed: bool = False,
    progress: bool = True,
    dashboard: bool = True,
    on_start: Callable[[dict[str, Any]], None] | None = None,
) -> BatchResult:
    """Runs the batch of ``items`` into ``out_dir`` (see the module) and returns what it did.

    ``client``: an open ``dask.distributed.Client`` to use (else one to ``scheduler``, ``"local"`` = a
    LocalCluster of ``workers`` one-thread processes, started only when some item must run).
    ``timeout``: seconds a task may run; ``retries``: re-runs of a task that raised an unexpected
    exception; ``on_start``: called with each task-start event (``item``, ``worker``, ``pid``)."""
    spec = spec or Spec()
    out = Path(out_dir)
    if client is None:
        check_scheduler(scheduler, workers)
    check_out_dir(out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    key = spec.key()
    hashes = _hashes(items, progress)
    journal_records = load_journal(out)
    records: dict[str, dict[str, Any]] = {}
    todo: list[tuple[Item, str]] = []
    adopted: list[dict[str, Any]] = []
    for it, h in zip(items, hashes, strict=True):
        rec = journal_records.get(it.name)
        if rec is not None and is_current(rec, h, key, out, rerun_failed):
            records[it.name] = rec
        elif (placed := _placed(out, it.name, h, key)) is not None:
            records[it.name] = placed  # finished, but the client stopped before recording it
            adopted.append(placed)
        else:
            todo.append((it, h))
    skipped = len(records)
    _remove_leftovers(out)
    result = BatchResult(out, records, len(todo), skipped, 0.0)
    if progress:
        print(f"bsv batch: {len(items)} items, {skipped} already done or failed with these inputs and "
              f"parameters, {len(todo)} to run -> {out}", flush=True)
    journal = Journal(out)
    for rec in adopted:
        journal.append(rec)
    try:
        with ResultsTable(out, [records[it.name] for it in items if it.name in records]) as table:
            if todo:
                opened = contextlib.nullcontext(client) if client is not None else open_client(
                    scheduler, workers, dashboard=dashboard)
                with opened as c:
                    result.dashboard = dashboard_text(c)
                    if progress:
                        print(result.dashboard, flush=True)
                    _run(c, todo, out, spec, table, journal, result, timeout, retries, progress, on_start)
    finally:
        journal.close()
        _remove_leftovers(out)  # also after Ctrl-C: the local cluster has stopped its workers by now
    result.wall_s = time.perf_counter() - t0
    return result


def _run(client: Any, todo: list[tuple[Item, str]], out: Path, spec: Spec, table: ResultsTable, journal: Journal,
         result: BatchResult, timeout: float | None, retries: int, progress: bool,
         on_start: Callable[[dict[str, Any]], None] | None) -> None:
    from distributed import as_completed
    from tqdm import tqdm

    starts = _Starts(on_start)
    topic = START_TOPIC
    client.subscribe_topic(topic, starts)
    run_id = uuid.uuid4().hex[:8]
    by_item = {it.name: it for it, _ in todo}
    hashes = {it.name: h for it, h in todo}
    key = spec.key()
    futures = {it.name: client.submit(run_item, it, str(out), spec, h, key=f"bsv-batch-{run_id}-{it.name}",
                                      retries=retries, pure=False) for it, h in todo}
    names = {f.key: n for n, f in futures.items()}
    timed_out: dict[str, str] = {}
    stop = threading.Event()
    watchdog = None
    if timeout is not None:
        watchdog = threading.Thread(target=_watchdog, args=(client, futures, starts, timeout, timed_out, stop),
                                    daemon=True)
        watchdog.start()
    failed = 0
    try:
        with tqdm(total=len(todo), desc="bsv batch", unit="item", disable=not progress, file=sys.stderr) as bar:
            for fut in as_completed(list(futures.values())):
                name = names[fut.key]
                item = by_item[name]
                if fut.status == "finished":
                    rec = fut.result()
                else:
                    rec = _placed(out, name, hashes[name], key) or {
                        "item": name, "kind": item.kind, "input": item.path, "input_hash": hashes[name],
                        "params_key": key, **_failure(name, item, fut, timed_out, timeout)}
                if rec.get("status") != "ok":
                    _remove_stale(out, name)
                with starts.lock:
                    attempts = starts.attempts.get(name, 0)
                    worker = starts.started.get(name, (0.0, ""))[1]
                rec.update(attempts=attempts, worker=worker or None, finished_utc=_now())
                with _deferred_interrupt():  # Ctrl-C lands after both: the table holds every journaled item
                    journal.append(rec)
                    table.add(rec)
                result.records[name] = rec
                if rec.get("status") != "ok":
                    failed += 1
                    bar.write(f"FAILED {name}: {rec.get('error_type')}: {rec.get('error')}")
                    bar.set_postfix(failed=failed)
                bar.update(1)
    finally:
        stop.set()
        if watchdog is not None:
            watchdog.join()
            # A timed-out task runs on until its worker's restart (done once the watchdog has joined)
            # and may have renamed its folder into place after the failure was recorded: a failed
            # item has no folder.
            for name in timed_out:
                if result.records.get(name, {}).get("status") != "ok":
                    _remove_stale(out, name)
        with contextlib.suppress(Exception):
            client.unsubscribe_topic(topic)
        pending = [f for f in futures.values() if not f.done()]
        if pending:
            client.cancel(pending)
        result.attempts = dict(starts.attempts)


def summary_text(res: BatchResult) -> str:
    """The lines printed at the end of ``bsv batch``."""
    head = (f"{len(res.done)} done, {len(res.failed)} failed ({res.ran} run, {res.skipped} skipped) in "
            f"{res.wall_s:.1f} s")
    lines = [head]
    for name in res.failed:
        r = res.records[name]
        lines.append(f"  failed {name}: {r.get('error_type')}: {r.get('error')}")
    lines.append(f"table: {res.out_dir / PARQUET_NAME}, {res.out_dir / CSV_NAME}")
    return "\n".join(lines)


__all__ = ["BatchResult", "check_out_dir", "run_batch", "summary_text"]

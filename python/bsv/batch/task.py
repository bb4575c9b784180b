"""One item on a Dask worker: the work, written atomically into ``DIR/<item>/``, returned as a record.

What a task receives is small (the :class:`~bsv.batch.items.Item` with its path, the output folder, the
:class:`~bsv.batch.state.Spec`): the worker reads the input from storage it shares with the client and
writes the outputs there; only the record (volumes, quality figures, timings; a few kB) comes back.

The outputs go into a temporary folder ``DIR/.tmp-<item>-<random>/`` renamed to ``DIR/<item>/`` once
complete (an older result of the item, from other parameters or another input, is replaced only then):
a failed or killed task leaves no item folder. A :class:`bsv.errors.BsvError` (corrupt file, failed
landmark check, impossible capture) is the item's recorded failure, never retried; any other exception
propagates so that Dask retries the task (``retries``) before the client records it.
"""

from __future__ import annotations

import json
import os
import shutil
import time
import uuid
from pathlib import Path
from typing import Any

from .items import Item
from .state import Spec

#: Topic of the event a task logs when it starts (the client times tasks and counts attempts with it).
START_TOPIC = "bsv-batch-start"
#: The record's copy inside each item folder.
ITEM_JSON = "item.json"


def _log_start(item: Item) -> None:
    try:
        from distributed import get_worker

        w = get_worker()
    except (ImportError, ValueError):
        return  # run outside a Dask worker (tests, the sequential path)
    w.log_event(START_TOPIC, {"item": item.name, "worker": w.address, "pid": os.getpid()})


def _cloud_item(item: Item, tmp: Path, spec: Spec) -> dict[str, Any]:
    from .. import read_point_cloud, register, write_mesh

    cloud = read_point_cloud(item.path)
    reg = register(cloud, density=spec.density, **spec.params)
    write_mesh(tmp / "fitted.ply", reg.mesh)
    (tmp / "volumes.json").write_text(json.dumps(reg.volumes, indent=2) + "\n")
    if spec.what == "report":
        from ..pipeline import ProcessResult
        from ..report import write_report

        res = ProcessResult(tmp, cloud, reg, reg.volumes, {"views": [], "warnings": []}, {},
                            {"register": reg.seconds})
        write_report(res, tmp, title=f"BSV batch: {item.name}")
    if spec.what == "bsip":
        from .. import bsip

        bsip(reg, out_dir=tmp)
    return {"volumes": reg.volumes, "cloud_points": len(cloud), "warnings": list(reg.volumes.get("notes") or [])}


def _capture_item(item: Item, tmp: Path, spec: Spec) -> dict[str, Any]:
    from ..pipeline import process

    res = process(item.path, item.calibration, tmp, segmentation=spec.segmentation, progress=False,
                  density=spec.density, title=f"BSV batch: {item.name}", bsip=spec.what == "bsip", **spec.params)
    # the cloud's floor check, the volumes' notes, and the camera path's landmark and template-pose warnings
    warnings = [*res.cloud_report.get("warnings", []), *(res.volumes.get("notes") or []), *res.warnings]
    return {"volumes": res.volumes, "cloud_points": len(res.cloud), "warnings": warnings}


def _place(tmp: Path, final: Path) -> None:
    """Renames the complete ``tmp`` folder to ``final``; an older ``final`` is moved aside first and removed."""
    old = None
    if final.exists():
        old = final.with_name(f".old-{final.name}-{uuid.uuid4().hex[:8]}")
        os.replace(final, old)
    os.replace(tmp, final)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def run_item(item: Item, out_dir: str, spec: Spec, input_hash: str) -> dict[str, Any]:
    """Processes one item on a worker and returns its record (status ``ok`` or ``failed``; see the
    module for what is raised instead)."""
    from .. import BsvError, __version__

    _log_start(item)
    t0 = time.perf_counter()
    out = Path(out_dir)
    tmp = out / f".tmp-{item.name}-{uuid.uuid4().hex[:12]}"
    tmp.mkdir()  # not tempfile.mkdtemp: its 0700 mode would stay on the item folder
    record: dict[str, Any] = {"item": item.name, "kind": item.kind, "input": item.path, "input_hash": input_hash,
                              "params_key": spec.key(), "bsv_version": __version__, "density_kg_m3": spec.density}
    try:
        work = _cloud_item(item, tmp, spec) if item.kind == "cloud" else _capture_item(item, tmp, spec)
    except BsvError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        return {**record, "status": "failed", "error_type": type(exc).__name__, "error": str(exc),
                "seconds": time.perf_counter() - t0}
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    vols = work["volumes"]
    reg = vols.get("registration") or {}
    record.update(status="ok", volumes_l=dict(vols.get("volumes_l") or {}), cloud_points=work["cloud_points"],
                  warnings="; ".join(str(w) for w in work["warnings"]) or None,
                  rms_mesh_to_points_mm=reg.get("rms_mesh_to_points_mm"),
                  rms_points_to_mesh_mm=reg.get("rms_points_to_mesh_mm"), iterations=reg.get("iterations"),
                  seconds=time.perf_counter() - t0)
    (tmp / ITEM_JSON).write_text(json.dumps(record, indent=1, sort_keys=True, default=str) + "\n")
    _place(tmp, out / item.name)
    return record


def noop(i: int) -> int:
    """A task that does nothing (the scheduler-overhead benchmark)."""
    return i


__all__ = ["ITEM_JSON", "START_TOPIC", "noop", "run_item"]

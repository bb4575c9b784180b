"""The job queue: captures and processings run one at a time in a separate worker process (spawned), so
the web workers never compute; the worker writes its progress (the pipeline's steps) into the job row,
which the job page polls.

Files are built in a temporary folder and renamed into place once complete, and the database rows are
added only then: a failed or killed run leaves no half-written capture, result or row, and the subject's
history as it was. The error message of the pipeline (a :class:`bsv.errors.BsvError`) is stored as the
job's message; other exceptions are stored by their type and text, never as a stack trace.
"""

from __future__ import annotations

import contextlib
import io
import logging
import multiprocessing
import os
import shutil
import threading
import time
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sqlalchemy import select

from ..types import SEXES
from .models import Job, Result, Session, Subject, utcnow

log = logging.getLogger("bsv.station")

#: Job kinds: a capture then its processing, a new processing of an existing session's capture, or a
#: preview (a short capture and the MediaPipe pose check, kept apart from the sessions).
KINDS = ("capture", "process", "preview")
#: Kinds that use the rig (one at a time).
RIG_KINDS = ("capture", "preview")
#: States in which a job still holds the rig (a second capture is refused meanwhile).
CAPTURE_BUSY = ("queued", "capturing")
#: States of a job not finished yet.
ACTIVE = ("queued", "capturing", "processing")
#: Steps of :func:`bsv.pipeline.process` with camera segmentation (keys of its timings: prepare, read,
#: calibration, segment, cloud, pose, register, intervals, report, write), for the progress fraction.
PROCESS_STEPS = 10
#: Sub-folders of the data folder.
CAPTURES, RESULTS, TMP, PREVIEWS = "captures", "results", "tmp", "previews"


def new_dir(data: Path, kind: str) -> tuple[Path, Path]:
    """A fresh temporary folder and its final place under ``data/kind`` (random names: no personal data)."""
    name = uuid.uuid4().hex
    (data / TMP).mkdir(parents=True, exist_ok=True)
    (data / kind).mkdir(parents=True, exist_ok=True)
    return data / TMP / f"{kind}-{name}", data / kind / name


class _StepWriter(io.TextIOBase):
    """Turns the pipeline's ``[bsv] <step> ...`` lines into the job's step and progress."""

    def __init__(self, update: Callable[[str, float], None], total: int, done: int = 0) -> None:
        self.update, self.total, self.done, self._buf = update, total, done, ""

    def write(self, s: str) -> int:
        self._buf += s
        while "\n" in self._buf:
            line, self._buf = self._buf.split("\n", 1)
            line = line.strip()
            if line.startswith("[bsv] ") and line.endswith(" ..."):
                self.update(line[6:-4][:120], min(self.done / self.total, 0.99))
            elif line.startswith("[bsv] ") and ": " in line and line.endswith(" s"):
                self.done += 1
        return len(s)


def _exit_with_parent() -> None:
    """End this worker as soon as the station that spawned it is gone (killed with -9): its job is marked
    interrupted by the next start, and no orphan keeps writing."""
    parent = os.getppid()

    def watch() -> None:
        while True:
            time.sleep(0.2)
            if os.getppid() != parent:
                os._exit(3)

    threading.Thread(target=watch, name="bsv-station-parent-watch", daemon=True).start()


def run_job(db_url: str, data_dir: str, job_id: int) -> None:
    """The worker process's entry point: run job ``job_id`` to its end (done or failed)."""
    from ..errors import BsvError
    from .db import make_engine, session_factory

    _exit_with_parent()

    data = Path(data_dir)
    engine = make_engine(db_url)
    factory = session_factory(engine)

    def update(**fields: Any) -> None:
        with factory() as db:
            job = db.get(Job, job_id)
            assert job is not None
            for k, v in fields.items():
                setattr(job, k, v)
            db.commit()

    tmp_dirs: list[Path] = []
    try:
        with factory() as db:
            job = db.get(Job, job_id)
            if job is None or job.state not in ACTIVE:
                return
            kind, params, operator, session_id = job.kind, dict(job.params), job.operator, job.session_id
            subject_id = job.subject_id
        if kind == "preview":
            _preview(data, params, update, tmp_dirs)
            return
        if kind == "capture":
            update(state="capturing", step="capturing", progress=0.0)
            tmp, final = new_dir(data, CAPTURES)
            tmp_dirs.append(tmp)
            source = params.get("source", "virtual")
            info = _capture(tmp, data, source, params, update)
            tmp.rename(final)
            tmp_dirs.remove(tmp)
            with factory() as db:
                ses = Session(subject_id=subject_id, capture_dir=str(final.relative_to(data)),
                              calibration=str((final / "calibration.json").relative_to(data)), source=source,
                              source_info=info, operator=operator)
                db.add(ses)
                db.flush()
                session_id = ses.id
                job = db.get(Job, job_id)
                assert job is not None
                job.session_id, job.state, job.step = session_id, "processing", "processing"
                db.commit()
        else:
            update(state="processing", step="processing", progress=0.0)
        assert session_id is not None
        with factory() as db:
            ses_row = db.get(Session, session_id)
            assert ses_row is not None
            cap, calib = data / ses_row.capture_dir, data / ses_row.calibration
        result_id = _process(data, cap, calib, session_id, params, operator, factory, tmp_dirs,
                             lambda step, p: update(step=step, progress=0.5 + 0.5 * p if kind == "capture" else p))
        update(step="drawing the subject's history chart", progress=0.99)
        try:
            with factory() as db:
                from .charts import subject_chart

                subj = db.get(Subject, subject_id)
                if subj is not None:
                    subject_chart(data, subj.sessions)
        except Exception:  # the chart is a cache: the subject page draws it if this failed
            log.warning("job %d: the history chart could not be drawn in the worker", job_id, exc_info=True)
        update(state="done", step="done", progress=1.0, result_id=result_id, finished_at=utcnow())
    except BsvError as e:
        update(state="failed", step="failed", message=str(e) or type(e).__name__, finished_at=utcnow())
    except Exception as e:
        log.exception("job %d failed", job_id)
        update(state="failed", step="failed", message=f"internal error ({type(e).__name__}): {e}",
               finished_at=utcnow())
    finally:
        for d in tmp_dirs:
            shutil.rmtree(d, ignore_errors=True)
        engine.dispose()


def _capture(tmp: Path, data: Path, source: str, params: dict[str, Any],
             update: Callable[..., None]) -> dict[str, Any]:
    from ..errors import CaptureError
    from . import rig

    if source == "virtual":
        update(step="rendering the virtual rig's two cameras", progress=0.05)
        return rig.render_virtual(tmp, params)
    station_cal = data / "calibration.json"
    if not station_cal.is_file():
        raise CaptureError(f"no station calibration: run `bsv calibrate` and copy its calibration.json to "
                           f"{station_cal}")
    update(step=f"{'replaying the recording' if source == 'replay' else 'capturing both cameras'}", progress=0.05)
    stop = threading.Event()
    if source == "realsense":  # the acquisition's progress bar: elapsed time of the still capture
        seconds = float(params.get("seconds", 5.0))

        def tick() -> None:
            t0 = time.monotonic()
            while not stop.wait(0.5):
                done = min((time.monotonic() - t0) / seconds, 1.0)
                update(step=f"capturing both cameras: {min(time.monotonic() - t0, seconds):.1f} / {seconds:.0f} s",
                       progress=0.05 + 0.4 * done)

        threading.Thread(target=tick, daemon=True).start()
    try:
        info = rig.record(tmp, source, params)
    finally:
        stop.set()
    shutil.copyfile(station_cal, tmp / "calibration.json")
    return info


def _preview(data: Path, params: dict[str, Any], update: Callable[..., None], tmp_dirs: list[Path]) -> None:
    """A capture into ``data/previews/<id>/capture`` (older previews are deleted: they show the subject)
    and the pose check: MediaPipe's segmentation of both colour images into ``.../segmentation``."""
    from ..errors import LandmarkMissingError, PersonNotFoundError
    from ..frontend.segment import segment_capture

    tmp, final = new_dir(data, PREVIEWS)
    tmp_dirs.append(tmp)
    tmp.mkdir()
    update(state="capturing", step="preview: capturing", progress=0.1)
    _capture(tmp / "capture", data, str(params.get("source", "virtual")), {**params, "seconds": 1.0}, update)
    update(step="pose check (MediaPipe landmarks on both colour images)", progress=0.6)
    note = ""
    try:
        segment_capture(tmp / "capture", out_dir=tmp / "segmentation")
    except (LandmarkMissingError, PersonNotFoundError) as e:
        note = f"pose check failed: {e}"
    for old in (data / PREVIEWS).iterdir():
        shutil.rmtree(old, ignore_errors=True)
    tmp.rename(final)
    tmp_dirs.remove(tmp)
    update(state="done", step="preview ready", progress=1.0, message=note, finished_at=utcnow(),
           params={**params, "preview_dir": str(final.relative_to(data))})


def _process(data: Path, cap: Path, calib: Path, session_id: int, params: dict[str, Any], operator: str,
             factory: Any, tmp_dirs: list[Path], update: Callable[[str, float], None]) -> int:
    from .. import __version__
    from ..pipeline import process

    tmp, final = new_dir(data, RESULTS)
    tmp_dirs.append(tmp)
    seg = str(params.get("segmentation", "camera"))
    with factory() as db:  # the subject's recorded sex picks the template of that sex ("other": the average one)
        ses = db.get(Session, session_id)
        subj = db.get(Subject, ses.subject_id) if ses is not None else None
        sex = subj.sex if subj is not None and subj.sex in SEXES else None
    writer = _StepWriter(update, PROCESS_STEPS)
    with contextlib.redirect_stdout(writer):
        res = process(cap, calib, tmp, segmentation=seg, progress=True, title="BSV Station report", sex=sex)
    tmp.rename(final)
    tmp_dirs.remove(tmp)
    with factory() as db:
        r = Result(session_id=session_id, volumes=res.volumes, report_dir=str(final.relative_to(data)),
                   software_version=__version__, operator=operator, parameters={"segmentation": seg, "sex": sex})
        db.add(r)
        db.commit()
        return int(r.id)


class JobRunner:
    """Runs the queued jobs one after the other, each in a fresh spawned worker process; wakes on
    :meth:`kick` or every ``poll_s`` seconds. At start, jobs left running by a killed server are marked
    failed ("interrupted") and their temporary folders removed."""

    def __init__(self, db_url: str, data: Path, factory: Any, poll_s: float = 1.0) -> None:
        self.db_url, self.data, self.factory, self.poll_s = db_url, data, factory, poll_s
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.current: Any = None

    def recover(self) -> None:
        """Mark jobs a dead server left in capturing/processing as failed; clear the temporary folder."""
        with self.factory() as db:
            for job in db.scalars(select(Job).where(Job.state.in_(("capturing", "processing")))):
                job.state, job.step, job.finished_at = "failed", "failed", utcnow()
                job.message = "interrupted: the station stopped while this job ran; start it again"
            db.commit()
        shutil.rmtree(self.data / TMP, ignore_errors=True)

    def start(self) -> None:
        """Start the runner thread."""
        self.recover()
        self._thread = threading.Thread(target=self._loop, name="bsv-station-jobs", daemon=True)
        self._thread.start()

    def kick(self) -> None:
        """Wake the runner (a job was queued)."""
        self._wake.set()

    def stop(self) -> None:
        """Stop the runner; a running worker process is terminated (its job is marked interrupted)."""
        self._stop.set()
        self._wake.set()
        proc = self.current
        if proc is not None and proc.is_alive():
            proc.terminate()
            proc.join(5)
        if self._thread is not None:
            self._thread.join(10)
        self.recover()

    def _next(self) -> int | None:
        with self.factory() as db:
            job = db.scalars(select(Job).where(Job.state == "queued").order_by(Job.id).limit(1)).first()
            return None if job is None else int(job.id)

    def _loop(self) -> None:
        ctx = multiprocessing.get_context("spawn")
        while not self._stop.is_set():
            job_id = self._next()
            if job_id is None:
                self._wake.wait(self.poll_s)
                self._wake.clear()
                continue
            proc = ctx.Process(target=run_job, args=(self.db_url, str(self.data), job_id), daemon=True)
            self.current = proc
            proc.start()
            proc.join()
            self.current = None
            if self._stop.is_set():
                break
            with self.factory() as db:
                job = db.get(Job, job_id)
                if job is not None and job.state in ACTIVE:
                    job.state, job.step, job.finished_at = "failed", "failed", utcnow()
                    job.message = f"the worker process stopped unexpectedly (exit code {proc.exitcode})"
                    db.commit()


__all__ = ["ACTIVE", "CAPTURE_BUSY", "KINDS", "RIG_KINDS", "JobRunner", "new_dir", "run_job"]

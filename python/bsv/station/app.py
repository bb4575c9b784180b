"""The station's web application (FastAPI, server-rendered Jinja2 pages, a little static JS).

:func:`create_app` builds it for a :class:`StationConfig`. Routes: subjects (list, create, find, page,
charts, compare, CSV export), captures (virtual rig, replay, live cameras, upload of a capture zip),
sessions and re-processing, jobs (page + JSON progress polled by the page), the rig's status, login,
the audit log. Ids in URLs are the database's integers (no subject code, no personal data); the subject
finder posts its query.
"""


import csv
import io
import re
import threading
import time
from collections.abc import AsyncIterator, Iterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

from fastapi import Depends, FastAPI, File, Form, HTTPException, Request, UploadFile
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates
from sqlalchemy import func, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session as DbSession
from starlette.middleware.sessions import SessionMiddleware

from ..errors import LoginRequired
from . import jobs as jobq
from . import rig, security, uncertainty
from .charts import result_template_kind, subject_chart, template_changes
from .db import default_url, make_engine, migrate, session_factory
from .models import AuditEvent, Job, Result, Session, Subject, utcnow
from .posecheck import A_POSE_DEG, pose_check
from .security import Principal

HERE = Path(__file__).parent
#: Pseudonymous subject codes: letters, digits, '_', '-', '.'; 1-32 characters.
CODE_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,31}$")
SEXES = ("female", "male", "other")
#: Largest upload accepted (a zipped capture).
MAX_UPLOAD = 400_000_000


@dataclass
class StationConfig:
    """Where the station keeps its data, which database it uses and where it listens."""

    data: Path
    db_url: str | None = None
    host: str = "127.0.0.1"
    port: int = 8000
    demo: bool = False
    run_jobs: bool = True

    @property
    def url(self) -> str:
        """The database URL (the embedded SQLite file unless ``db_url``)."""
        return self.db_url or default_url(self.data)

    @property
    def require_login(self) -> bool:
        """Login is required on every address but localhost."""
        return not security.is_loopback(self.host)


@dataclass
class RigJobForm:
    """The form of a rig job, a capture or a preview (one FastAPI dependency of both routes): the source
    (:data:`bsv.station.rig.SOURCES`), the virtual rig's subject (``index``, ``seed``, ``swollen``
    segment) and its seed, the segmentation ("camera" or "oracle") and a replay's recording folder."""

    source: Annotated[str, Form()] = "virtual"
    swollen: Annotated[str, Form()] = ""
    index: Annotated[int, Form(ge=0, le=10_000)] = 0
    seed: Annotated[int, Form(ge=0, le=2**31)] = 0
    rig_seed: Annotated[int, Form(ge=0, le=2**31)] = 0
    segmentation: Annotated[str, Form()] = "camera"
    recording_dir: Annotated[str, Form()] = ""


def _fmt(t: Any) -> str:
    return t.strftime("%Y-%m-%d %H:%M UTC") if t is not None else ""


def create_app(config: StationConfig) -> FastAPI:
    """The station application for ``config`` (migrates the database; starts the job runner on startup)."""
    config.data.mkdir(parents=True, exist_ok=True)
    engine = make_engine(config.url)
    migrate(engine)
    factory = session_factory(engine)
    runner = jobq.JobRunner(config.url, config.data, factory)
    templates = Jinja2Templates(directory=str(HERE / "templates"))
    templates.env.filters["fmt"] = _fmt
    templates.env.filters["template_kind"] = result_template_kind
    submit_lock = threading.Lock()

    @asynccontextmanager
    async def lifespan(_app: FastAPI) -> AsyncIterator[None]:
        if config.demo:
            _seed_demo(factory)
        if config.run_jobs:
            runner.start()
        yield
        if config.run_jobs:
            runner.stop()
        engine.dispose()

    app = FastAPI(title="BSV Station", lifespan=lifespan, docs_url=None, redoc_url=None, openapi_url=None)
    app.state.config, app.state.engine, app.state.factory, app.state.runner = config, engine, factory, runner
    app.add_middleware(SessionMiddleware, secret_key=security.secret_key(config.data), same_site="strict",
                       max_age=8 * 3600, session_cookie="bsv_station")
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")

    # ---------------------------------------------------------------- dependencies and errors

    def get_db() -> Iterator[DbSession]:
        with factory() as db:
            yield db

    def principal(request: Request) -> Principal:
        if not config.require_login:
            return security.LOCAL
        name, role = request.session.get("user"), request.session.get("role")
        if isinstance(name, str) and role in security.ROLES:
            return Principal(name, role)
        raise LoginRequired()

    def operator(who: Annotated[Principal, Depends(principal)]) -> Principal:
        if not who.can_operate:
            raise HTTPException(403, "this needs the operator role; ask an operator")
        return who

    async def csrf(request: Request) -> None:
        form = await request.form()
        token = form.get("csrf_token")
        if not security.csrf_ok(request.session, token if isinstance(token, str) else None):
            raise HTTPException(403, "the form expired or came from another site (CSRF check); reload the page "
                                     "and submit again")

    Db = Annotated[DbSession, Depends(get_db)]
    Who = Annotated[Principal, Depends(principal)]
    Op = Annotated[Principal, Depends(operator)]
    Csrf = Depends(csrf)
    RigForm = Annotated[RigJobForm, Depends()]

    def page(request: Request, name: str, who: Principal | None, status: int = 200, **ctx: Any) -> HTMLResponse:
        ctx.update(who=who, csrf=security.csrf_token(request.session), login=config.require_login)
        return templates.TemplateResponse(request, name, ctx, status_code=status)

    def wants_json(request: Request) -> bool:
        return request.url.path.startswith("/api/")

    @app.exception_handler(LoginRequired)
    async def _login(request: Request, _exc: LoginRequired) -> Response:
        if wants_json(request) or request.method != "GET":
            return JSONResponse({"detail": "login required"}, status_code=401)
        return RedirectResponse("/login", status_code=303)

    @app.exception_handler(HTTPException)
    async def _http(request: Request, exc: HTTPException) -> Response:
        if wants_json(request):
            return JSONResponse({"detail": exc.detail}, status_code=exc.status_code)
        return page(request, "error.html", None, exc.status_code, message=str(exc.detail), code=exc.status_code)

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError) -> Response:
        parts = []
        for err in exc.errors():
            loc = ".".join(str(x) for x in err.get("loc", ()) if x not in ("body", "path", "query"))
            parts.append(f"{loc}: {err.get('msg', 'invalid')}")
        msg = "malformed request: " + "; ".join(parts)
        if wants_json(request):
            return JSONResponse({"detail": msg}, status_code=422)
        return page(request, "error.html", None, 422, message=msg, code=422)

    def get_or_404(db: DbSession, model: Any, ident: int, what: str) -> Any:
        row = db.get(model, ident)
        if row is None:
            raise HTTPException(404, f"{what} {ident} does not exist")
        return row

    # ---------------------------------------------------------------- subjects

    @app.get("/healthz")
    def healthz() -> dict[str, str]:
        return {"status": "ok"}

    @app.get("/", response_class=HTMLResponse)
    def index(request: Request, db: Db, who: Who) -> HTMLResponse:
        counts = dict(db.execute(select(Session.subject_id, func.count(Session.id)).group_by(Session.subject_id)).all())
        subjects = db.scalars(select(Subject).order_by(Subject.id.desc()).limit(500)).all()
        active = db.scalars(select(Job).where(Job.state.in_(jobq.ACTIVE)).order_by(Job.id)).all()
        return page(request, "index.html", who, subjects=subjects, counts=counts, active=active, sexes=SEXES)

    @app.post("/subjects", dependencies=[Csrf])
    def create_subject(db: Db, who: Op, code: Annotated[str, Form()], sex: Annotated[str, Form()],
                       birth_year: Annotated[str, Form()] = "", height_m: Annotated[str, Form()] = "",
                       mass_kg: Annotated[str, Form()] = "", notes: Annotated[str, Form()] = "") -> Response:
        fields = _subject_fields(code, sex, birth_year, height_m, mass_kg, notes)
        if db.scalars(select(Subject).where(Subject.code == fields["code"])).first() is not None:
            raise HTTPException(409, "a subject with this code exists already; use the finder")
        subj = Subject(**fields)
        db.add(subj)
        try:
            db.flush()
        except IntegrityError as e:
            db.rollback()
            raise HTTPException(409, "a subject with this code exists already; use the finder") from e
        security.audit(db, who, "create_subject", f"subject:{subj.id}")
        db.commit()
        return RedirectResponse(f"/subjects/{subj.id}", status_code=303)

    @app.post("/subjects/find", dependencies=[Csrf])
    def find_subject(db: Db, who: Who, code: Annotated[str, Form()]) -> Response:
        subj = db.scalars(select(Subject).where(Subject.code == code.strip())).first()
        if subj is None:
            raise HTTPException(404, "no subject has this code")
        return RedirectResponse(f"/subjects/{subj.id}", status_code=303)

    @app.get("/subjects/{subject_id}", response_class=HTMLResponse)
    def subject_page(request: Request, db: Db, who: Who, subject_id: int) -> HTMLResponse:
        subj: Subject = get_or_404(db, Subject, subject_id, "subject")
        sessions = list(subj.sessions)
        done = [s for s in sessions if s.latest is not None]
        chart = ""
        sources: set[str] = set()
        if done:
            vols = [s.latest.volumes for s in done if s.latest is not None]
            chart = subject_chart(config.data, done)
            for v in vols:
                for name in uncertainty.SEGMENTS:
                    iv = uncertainty.volume_interval(v, name)
                    if iv is not None:
                        sources.add(iv.source)
        active = db.scalars(select(Job).where(Job.subject_id == subj.id, Job.state.in_(jobq.ACTIVE))).all()
        failed = db.scalars(select(Job).where(Job.subject_id == subj.id, Job.state == "failed")
                            .order_by(Job.id.desc()).limit(5)).all()
        security.audit(db, who, "view_subject", f"subject:{subj.id}")
        db.commit()
        return page(request, "subject.html", who, subject=subj, sessions=sessions, done=done, chart=chart,
                    template_changed=_template_changed(done),
                    interval_label=uncertainty.source_label(sources) if sources else "", active=active,
                    failed=failed, swellings=sorted(rig.SWELLINGS), sources=rig.SOURCES, segments=uncertainty.SEGMENTS)

    @app.get("/subjects/{subject_id}/compare", response_class=HTMLResponse)
    def compare_page(request: Request, db: Db, who: Who, subject_id: int, a: int, b: int) -> HTMLResponse:
        subj: Subject = get_or_404(db, Subject, subject_id, "subject")
        sa, sb = get_or_404(db, Session, a, "session"), get_or_404(db, Session, b, "session")
        if sa.subject_id != subj.id or sb.subject_id != subj.id:
            raise HTTPException(404, "both sessions must belong to this subject")
        if sa.latest is None or sb.latest is None:
            raise HTTPException(409, "a session to compare has no result yet; process it first")
        changes = uncertainty.compare(sa.latest.volumes, sb.latest.volumes)
        label = uncertainty.source_label({s for c in changes for s in c.sources})
        kinds = [result_template_kind(r.volumes) for r in (sa.latest, sb.latest)]
        security.audit(db, who, "view_compare", f"subject:{subj.id}")
        db.commit()
        return page(request, "compare.html", who, subject=subj, a=sa, b=sb, changes=changes, interval_label=label,
                    templates=kinds if kinds[0] != kinds[1] else None)

    @app.get("/subjects/{subject_id}/export.csv")
    def export_csv(db: Db, who: Who, subject_id: int) -> Response:
        subj: Subject = get_or_404(db, Subject, subject_id, "subject")
        buf = io.StringIO()
        w = csv.writer(buf)
        head = ["subject_code", "session_id", "session_utc", "source", "result_id", "result_utc", "software_version",
                "template", "operator", "interval_source"]
        for s in uncertainty.SEGMENTS:
            head += [f"{s}_l", f"{s}_lo_l", f"{s}_hi_l"]
        for r in uncertainty.ASYMMETRIES:
            head += [r, f"{r}_lo", f"{r}_hi"]
        w.writerow(head)
        for ses in subj.sessions:
            for res in ses.results:
                row: list[Any] = [subj.code, ses.id, _fmt(ses.created_at), ses.source, res.id, _fmt(res.created_at),
                                  res.software_version, result_template_kind(res.volumes), res.operator]
                cells: list[Any] = []
                srcs = set()
                for s in uncertainty.SEGMENTS:
                    iv = uncertainty.volume_interval(res.volumes, s)
                    cells += ["", "", ""] if iv is None else [f"{iv.value:.4f}", f"{iv.lo:.4f}", f"{iv.hi:.4f}"]
                    if iv is not None:
                        srcs.add(iv.source)
                for r in uncertainty.ASYMMETRIES:
                    iv = uncertainty.ratio_interval(res.volumes, r)
                    cells += ["", "", ""] if iv is None else [f"{iv.value:.2f}", f"{iv.lo:.2f}", f"{iv.hi:.2f}"]
                w.writerow([*row, uncertainty.source_label(srcs) if srcs else "", *cells])
        security.audit(db, who, "export_csv", f"subject:{subj.id}")
        db.commit()
        return Response(buf.getvalue(), media_type="text/csv",
                        headers={"Content-Disposition": f'attachment; filename="subject-{subj.id}-history.csv"'})

    @app.get("/subjects/{subject_id}/export.pdf")
    def export_pdf(db: Db, who: Who, subject_id: int) -> Response:
        subj: Subject = get_or_404(db, Subject, subject_id, "subject")
        try:
            import weasyprint
        except ImportError as e:
            raise HTTPException(501, "PDF export needs weasyprint (pip install -r requirements-station.txt)") from e
        done = [s for s in subj.sessions if s.latest is not None]
        cells = {s.id: {n: uncertainty.volume_interval(s.latest.volumes, n) for n in uncertainty.SEGMENTS}
                 for s in done if s.latest is not None}
        sources = {iv.source for row in cells.values() for iv in row.values() if iv is not None}
        chart = subject_chart(config.data, done)
        html = templates.get_template("history_pdf.html").render(
            subject=subj, done=done, cells=cells, segments=uncertainty.SEGMENTS, chart=chart, now=utcnow(),
            template_changed=_template_changed(done),
            interval_label=uncertainty.source_label(sources) if sources else "no result yet")
        pdf = weasyprint.HTML(string=html).write_pdf()
        security.audit(db, who, "export_pdf", f"subject:{subj.id}")
        db.commit()
        return Response(pdf, media_type="application/pdf",
                        headers={"Content-Disposition": f'attachment; filename="subject-{subj.id}-history.pdf"'})

    # ---------------------------------------------------------------- captures and jobs

    def queue(db: DbSession, job: Job) -> Job:
        db.add(job)
        db.flush()
        security.audit(db, Principal(job.operator, "operator"), f"queue_{job.kind}", f"job:{job.id}")
        db.commit()
        runner.kick()
        return job

    def rig_job(db: DbSession, who: Principal, subject_id: int, kind: str, form: RigJobForm) -> Response:
        subj: Subject = get_or_404(db, Subject, subject_id, "subject")
        if form.source not in rig.SOURCES:
            raise HTTPException(400, f"source must be one of {', '.join(rig.SOURCES)}")
        if form.swollen and form.swollen not in rig.SWELLINGS:
            raise HTTPException(400, f"swollen segment must be one of {', '.join(sorted(rig.SWELLINGS))}")
        if form.segmentation not in ("camera", "oracle"):
            raise HTTPException(400, "segmentation must be camera (MediaPipe) or oracle (virtual rig only)")
        if form.segmentation == "oracle" and form.source != "virtual":
            raise HTTPException(400, "oracle segmentation exists only on the virtual rig")
        if form.source == "replay" and not form.recording_dir:
            raise HTTPException(400, "a replay needs the folder of the recording (front/ and back/ recording.db3)")
        params: dict[str, Any] = {"source": form.source, "segmentation": form.segmentation}
        if form.source == "virtual":
            params.update(index=form.index, seed=form.seed, rig_seed=form.rig_seed, swollen=form.swollen or None,
                          condition="l515")
        if form.source == "replay":
            params["recording_dir"] = form.recording_dir
        with submit_lock:
            busy = db.scalars(select(Job).where(Job.kind.in_(jobq.RIG_KINDS), Job.state.in_(jobq.CAPTURE_BUSY))).first()
            if busy is not None:
                raise HTTPException(409, f"a capture is already running (job {busy.id}); wait until it is processed")
            job = queue(db, Job(kind=kind, subject_id=subj.id, params=params, operator=who.name))
        return RedirectResponse(f"/jobs/{job.id}", status_code=303)

    @app.post("/subjects/{subject_id}/captures", dependencies=[Csrf])
    def start_capture(db: Db, who: Op, subject_id: int, form: RigForm) -> Response:
        return rig_job(db, who, subject_id, "capture", form)

    @app.post("/subjects/{subject_id}/previews", dependencies=[Csrf])
    def start_preview(db: Db, who: Op, subject_id: int, form: RigForm) -> Response:
        return rig_job(db, who, subject_id, "preview", form)

    @app.get("/jobs/{job_id}/preview/{camera}/{name}")
    def preview_file(db: Db, who: Who, job_id: int, camera: str, name: str) -> Response:
        job: Job = get_or_404(db, Job, job_id, "job")
        if camera not in ("front", "back") or name not in ("color.png", "segmentation.png"):
            raise HTTPException(400, "camera must be front or back, the file color.png or segmentation.png")
        folder = job.params.get("preview_dir")
        sub = "capture" if name == "color.png" else "segmentation"
        path = config.data / str(folder) / sub / camera / name if folder else None
        if path is None or not path.is_file():
            raise HTTPException(404, f"job {job_id} has no preview {camera}/{name} (previews are replaced by newer ones)")
        return _label_png(path) if name == "segmentation.png" else FileResponse(path)

    @app.post("/subjects/{subject_id}/uploads", dependencies=[Csrf])
    def upload_capture(db: Db, who: Op, subject_id: int, file: Annotated[UploadFile, File()],
                       segmentation: Annotated[str, Form()] = "camera") -> Response:
        subj: Subject = get_or_404(db, Subject, subject_id, "subject")
        if segmentation not in ("camera", "oracle"):
            raise HTTPException(400, "segmentation must be camera (MediaPipe) or oracle")
        data = file.file.read(MAX_UPLOAD + 1)
        if len(data) > MAX_UPLOAD:
            raise HTTPException(413, f"the upload is larger than {MAX_UPLOAD // 1_000_000} MB")
        from ..errors import BsvError

        tmp, final = jobq.new_dir(config.data, jobq.CAPTURES)
        try:
            rig.check_capture_zip(data, tmp)
        except BsvError as e:
            import shutil

            shutil.rmtree(tmp, ignore_errors=True)
            raise HTTPException(400, str(e)) from e
        tmp.rename(final)
        ses = Session(subject_id=subj.id, capture_dir=str(final.relative_to(config.data)),
                      calibration=str((final / rig.CALIBRATION).relative_to(config.data)), source="upload",
                      source_info={}, operator=who.name)
        db.add(ses)
        db.flush()
        job = queue(db, Job(kind="process", subject_id=subj.id, session_id=ses.id,
                            params={"segmentation": segmentation}, operator=who.name))
        return RedirectResponse(f"/jobs/{job.id}", status_code=303)

    @app.get("/sessions/{session_id}", response_class=HTMLResponse)
    def session_page(request: Request, db: Db, who: Who, session_id: int) -> HTMLResponse:
        ses: Session = get_or_404(db, Session, session_id, "session")
        rows = []
        if ses.latest is not None:
            for name in uncertainty.SEGMENTS:
                iv = uncertainty.volume_interval(ses.latest.volumes, name)
                if iv is not None:
                    rows.append((name, iv))
        truth = (ses.source_info or {}).get("true_volumes_l", {})
        pose = None if ses.latest is None else pose_check(config.data / ses.latest.report_dir)
        security.audit(db, who, "view_session", f"session:{ses.id}")
        db.commit()
        return page(request, "session.html", who, ses=ses, rows=rows, truth=truth, pose=pose, a_pose=A_POSE_DEG)

    @app.post("/sessions/{session_id}/process", dependencies=[Csrf])
    def reprocess(db: Db, who: Op, session_id: int, segmentation: Annotated[str, Form()] = "camera") -> Response:
        ses: Session = get_or_404(db, Session, session_id, "session")
        if segmentation not in ("camera", "oracle"):
            raise HTTPException(400, "segmentation must be camera (MediaPipe) or oracle")
        job = queue(db, Job(kind="process", subject_id=ses.subject_id, session_id=ses.id,
                            params={"segmentation": segmentation}, operator=who.name))
        return RedirectResponse(f"/jobs/{job.id}", status_code=303)

    @app.get("/results/{result_id}/files/{name}")
    def result_file(db: Db, who: Who, result_id: int, name: str) -> Response:
        res: Result = get_or_404(db, Result, result_id, "result")
        if not re.fullmatch(r"[A-Za-z0-9_-]+\.(html|png|json|ply|pdf|csv)", name):
            raise HTTPException(400, "file name must be a plain report file name (report.html, report.pdf, volumes.csv, *.png, volumes.json)")
        path = config.data / res.report_dir / name
        if not path.is_file():
            raise HTTPException(404, f"result {result_id} has no file {name}")
        if name == "report.html":
            security.audit(db, who, "view_report", f"result:{res.id}")
            db.commit()
        return FileResponse(path)

    @app.get("/sessions/{session_id}/capture/{camera}/color.png")
    def capture_colour(db: Db, who: Who, session_id: int, camera: str) -> Response:
        ses: Session = get_or_404(db, Session, session_id, "session")
        if camera not in ("front", "back"):
            raise HTTPException(400, "camera must be front or back")
        path = config.data / ses.capture_dir / camera / "color.png"
        if not path.is_file():
            raise HTTPException(404, f"session {session_id} has no {camera} colour image")
        return FileResponse(path)

    @app.get("/results/{result_id}/segmentation/{camera}/segmentation.png")
    def result_segmentation(db: Db, who: Who, result_id: int, camera: str) -> Response:
        res: Result = get_or_404(db, Result, result_id, "result")
        if camera not in ("front", "back"):
            raise HTTPException(400, "camera must be front or back")
        path = config.data / res.report_dir / "segmentation" / camera / "segmentation.png"
        if not path.is_file():
            raise HTTPException(404, f"result {result_id} has no {camera} segmentation image")
        return _label_png(path)

    @app.get("/jobs/{job_id}", response_class=HTMLResponse)
    def job_page(request: Request, db: Db, who: Who, job_id: int) -> HTMLResponse:
        job: Job = get_or_404(db, Job, job_id, "job")
        folder = job.params.get("preview_dir") if job.kind == "preview" else None
        pose = pose_check(config.data / str(folder)) if folder and (config.data / str(folder)).is_dir() else None
        rig_params = {k: v for k, v in job.params.items() if k in ("source", "index", "seed", "rig_seed", "swollen",
                                                                    "segmentation", "recording_dir") and v is not None}
        return page(request, "job.html", who, job=job, pose=pose, a_pose=A_POSE_DEG, preview=bool(pose or folder),
                    rig_params=rig_params)

    @app.get("/api/jobs/{job_id}")
    def job_json(db: Db, who: Who, job_id: int) -> dict[str, Any]:
        job: Job = get_or_404(db, Job, job_id, "job")
        return {"id": job.id, "kind": job.kind, "state": job.state, "step": job.step, "progress": job.progress,
                "message": job.message, "subject_id": job.subject_id, "session_id": job.session_id,
                "result_id": job.result_id}

    # ---------------------------------------------------------------- rig, login, audit

    status_cache: dict[str, Any] = {}

    @app.get("/rig", response_class=HTMLResponse)
    def rig_page(request: Request, who: Who) -> HTMLResponse:
        now = time.monotonic()
        if not status_cache or now - status_cache["at"] > 5.0:
            status_cache.update(rig.camera_status(), at=now)
        calibrated = (config.data / "calibration.json").is_file()
        return page(request, "rig.html", who, cams=status_cache, calibrated=calibrated, data=str(config.data))

    camera_lock = threading.Lock()

    @app.get("/rig/alignment/{camera}.jpg")
    def alignment_image(db: Db, who: Who, camera: str) -> Response:
        if camera not in ("front", "back"):
            raise HTTPException(400, "camera must be front or back")
        from ..errors import BsvError

        busy = db.scalars(select(Job).where(Job.kind.in_(jobq.RIG_KINDS), Job.state.in_(("capturing",)))).first()
        if busy is not None or not camera_lock.acquire(timeout=5):
            raise HTTPException(409, "the cameras are busy (a capture or another view); try again in a moment")
        try:
            jpg = rig.alignment_frame(camera)
        except BsvError as e:
            raise HTTPException(503, str(e)) from e
        finally:
            camera_lock.release()
        return Response(jpg, media_type="image/jpeg", headers={"Cache-Control": "no-store"})

    @app.get("/login", response_class=HTMLResponse)
    def login_page(request: Request) -> HTMLResponse:
        return page(request, "login.html", None)

    @app.post("/login", dependencies=[Csrf])
    def login(request: Request, db: Db, name: Annotated[str, Form()], password: Annotated[str, Form()]) -> Response:
        who = security.authenticate(db, name, password)
        if who is None:
            security.audit(db, Principal("?", "viewer"), "login_failed", "")
            db.commit()
            raise HTTPException(401, "wrong user name or password")
        request.session.clear()
        request.session.update(user=who.name, role=who.role)
        security.audit(db, who, "login", "")
        db.commit()
        return RedirectResponse("/", status_code=303)

    @app.post("/logout", dependencies=[Csrf])
    def logout(request: Request) -> Response:
        request.session.clear()
        return RedirectResponse("/login" if config.require_login else "/", status_code=303)

    @app.get("/audit", response_class=HTMLResponse)
    def audit_page(request: Request, db: Db, who: Op) -> HTMLResponse:
        events = db.scalars(select(AuditEvent).order_by(AuditEvent.id.desc()).limit(300)).all()
        return page(request, "audit.html", who, events=events)

    return app


def _template_changed(done: list[Session]) -> set[int]:
    """The ids of the sessions of ``done`` (oldest first, each with a result) whose latest result was fitted
    with another template than the session before them (:func:`bsv.station.charts.template_changes`)."""
    kinds = [result_template_kind(s.latest.volumes) if s.latest is not None else "" for s in done]
    return {done[i].id for i in template_changes(kinds)}


def _label_png(path: Path) -> Response:
    """A segment-id image (uint8) painted with the segment palette of :mod:`bsv.palette` (0: black)."""
    import cv2

    from ..palette import colourise

    ids = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if ids is None or ids.ndim != 2:
        raise HTTPException(404, "the segmentation image cannot be read")
    rgb = colourise(ids, background=(0, 0, 0))
    ok, png = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise HTTPException(500, "the segmentation image could not be encoded")
    return Response(png.tobytes(), media_type="image/png")


def _subject_fields(code: str, sex: str, birth_year: str, height_m: str, mass_kg: str, notes: str) -> dict[str, Any]:
    """The checked fields of the subject form; HTTP 400 naming the field otherwise."""
    code = code.strip()
    if not CODE_RE.fullmatch(code):
        raise HTTPException(400, "code: 1-32 letters, digits, '_', '-' or '.', starting with a letter or digit "
                                 "(a pseudonymous code, never a name)")
    if sex not in SEXES:
        raise HTTPException(400, f"sex must be one of {', '.join(SEXES)}")

    def num(text: str, name: str, lo: float, hi: float, unit: str) -> float | None:
        if not text.strip():
            return None
        try:
            v = float(text)
        except ValueError as e:
            raise HTTPException(400, f"{name}: {text[:20]!r} is not a number") from e
        if not lo <= v <= hi:
            raise HTTPException(400, f"{name} must lie in {lo:g}-{hi:g} {unit}")
        return v

    year = num(birth_year, "birth year", 1900, utcnow().year, "")
    if year is not None and year != int(year):
        raise HTTPException(400, "birth year must be a whole year")
    if len(notes) > 4000:
        raise HTTPException(400, "notes: at most 4000 characters")
    return {"code": code, "sex": sex, "birth_year": None if year is None else int(year),
            "height_m": num(height_m, "height", 0.5, 2.6, "m"), "mass_kg": num(mass_kg, "scale mass", 2, 400, "kg"),
            "notes": notes}


def _seed_demo(factory: Any) -> None:
    """The demo's sample subject and its first virtual-rig session (only into an empty database)."""
    with factory() as db:
        if db.scalars(select(Subject).limit(1)).first() is not None:
            return
        subj = Subject(code="DEMO-001", sex="female", birth_year=1990, height_m=1.63, mass_kg=62.0,
                       notes="sample subject of bsv station --demo (virtual rig, cohort subject 0)")
        db.add(subj)
        db.flush()
        db.add(Job(kind="capture", subject_id=subj.id, operator="demo",
                   params={"source": "virtual", "segmentation": "camera", "index": 0, "seed": 0, "rig_seed": 0,
                           "swollen": None, "condition": "l515"}))
        db.commit()


__all__ = ["CODE_RE", "SEXES", "StationConfig", "create_app"]

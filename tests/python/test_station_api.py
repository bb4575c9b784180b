"""BSV Station API tests (fastapi TestClient): every route, bad input -> 4xx with a message and nothing
written, the comparison rule with and without the pipeline's intervals, login/CSRF/roles/audit, backup,
and one real virtual-rig job (oracle segmentation) plus one failing job through the worker process."""

from __future__ import annotations

import io
import math
import re
import tarfile
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("fastapi", reason="BSV Station needs requirements-station.txt (scripts/setup.sh installs it)")

from fastapi.testclient import TestClient
from sqlalchemy import func, select

from bsv.station import StationConfig, create_app, rig, uncertainty
from bsv.station.models import AuditEvent, Job, Result, Session, Subject

TOKEN = re.compile(r'name="csrf_token" value="([^"]+)"')
#: Set to a PostgreSQL URL (postgresql+psycopg://user@host:port/db, an empty database the tests may wipe)
#: to run these tests on PostgreSQL instead of the embedded SQLite.
DB_ENV = "BSV_STATION_TEST_DB"


def _config(data: Path, **kw: Any) -> StationConfig:
    """A station config on the embedded SQLite, or on the (wiped) database of $BSV_STATION_TEST_DB."""
    import os

    url = os.environ.get(DB_ENV)
    if url:
        from sqlalchemy import create_engine, text

        engine = create_engine(url)
        with engine.begin() as conn:
            conn.execute(text("DROP SCHEMA public CASCADE"))
            conn.execute(text("CREATE SCHEMA public"))
        engine.dispose()
    return StationConfig(data=data, db_url=url or None, **kw)


def _token(c: TestClient) -> str:
    m = TOKEN.search(c.get("/login").text)
    assert m is not None
    return m.group(1)


def _count(app: Any, model: Any) -> int:
    with app.state.factory() as db:
        return int(db.scalar(select(func.count()).select_from(model)))


@pytest.fixture
def station(tmp_path: Path) -> Iterator[tuple[TestClient, Any, str]]:
    """A station on localhost with the job runner off (jobs stay queued)."""
    app = create_app(_config(tmp_path / "data", run_jobs=False))
    with TestClient(app) as c:
        yield c, app, _token(c)


def _subject(c: TestClient, tok: str, code: str = "P-001") -> int:
    r = c.post("/subjects", data={"csrf_token": tok, "code": code, "sex": "female", "birth_year": "1980",
                                  "height_m": "1.65", "mass_kg": "60.5", "notes": "left arm"}, follow_redirects=False)
    assert r.status_code == 303, r.text
    loc = r.headers["location"]
    assert re.fullmatch(r"/subjects/\d+", loc) and code not in loc  # no personal data in URLs
    return int(loc.rsplit("/", 1)[1])


def _volumes(forearm_l: float, intervals: dict[str, Any] | None = None) -> dict[str, Any]:
    v = {"torso": 34.0, "upper_arm_l": 1.65, "upper_arm_r": 1.63, "forearm_l": forearm_l, "forearm_r": 0.76,
         "thigh_l": 8.0, "thigh_r": 7.7, "shin_l": 2.8, "shin_r": 2.8}
    v["trunk_limbs"] = sum(v.values())
    out: dict[str, Any] = {"volumes_l": v, "ratios": {"asymmetry_forearm_pct": 200 * (forearm_l - 0.76) / (forearm_l + 0.76)}}
    if intervals is not None:
        out["intervals"] = intervals
    return out


def _session(app: Any, subject_id: int, volumes: dict[str, Any] | None) -> int:
    with app.state.factory() as db:
        s = Session(subject_id=subject_id, capture_dir="captures/x", calibration="captures/x/calibration.json",
                    source="virtual", source_info={}, operator="local")
        db.add(s)
        db.flush()
        if volumes is not None:
            db.add(Result(session_id=s.id, volumes=volumes, report_dir="results/x", software_version="t",
                          operator="local", parameters={}))
        db.commit()
        return int(s.id)


# ------------------------------------------------------------------------------------------------ rules


def test_compare_flags_only_changes_beyond_the_combined_uncertainty() -> None:
    a, b = _volumes(1.00), _volumes(1.28)
    rows = {c.segment: c for c in uncertainty.compare(a, b)}
    assert rows["forearm_l"].significant and rows["forearm_l"].change_ml == pytest.approx(280.0)
    assert rows["forearm_l"].change_pct == pytest.approx(28.0)
    # table: 9.4 % half-widths -> sqrt(94^2 + 120.3^2) mL
    assert rows["forearm_l"].combined_ml == pytest.approx(((0.094 * 1.0) ** 2 + (0.094 * 1.28) ** 2) ** 0.5 * 1e3)
    assert not any(c.significant for n, c in rows.items() if n not in ("forearm_l", "trunk_limbs"))
    assert rows["forearm_l"].sources == ("table", "table")
    # +8 % on a forearm stays within the table's uncertainty (13 %)
    assert not {c.segment: c for c in uncertainty.compare(a, _volumes(1.08))}["forearm_l"].significant


def test_compare_uses_the_pipeline_intervals_when_present() -> None:
    tight = {"level": 0.95, "volumes_l": {"forearm_l": [0.99, 1.01]}, "ratios": {}}
    tight_b = {"level": 0.95, "volumes_l": {"forearm_l": [1.07, 1.09]}, "ratios": {}}
    rows = {c.segment: c for c in uncertainty.compare(_volumes(1.0, tight), _volumes(1.08, tight_b))}
    assert rows["forearm_l"].significant and rows["forearm_l"].sources == ("pipeline", "pipeline")
    assert rows["forearm_l"].combined_ml == pytest.approx(2 ** 0.5 * 10.0)
    assert rows["torso"].sources == ("table", "table")
    bad = {"volumes_l": {"forearm_l": [1.1, 0.9]}}  # lo > hi: ignored, the table is used
    assert uncertainty.volume_interval(_volumes(1.0, bad), "forearm_l").source == "table"  # type: ignore[union-attr]


def test_virtual_rig_swells_only_the_chosen_segment() -> None:
    _, base = rig.virtual_body(0, 0, None)
    _, swollen = rig.virtual_body(0, 0, "forearm_l")
    growth = {k: swollen[k] / base[k] - 1 for k in uncertainty.SEGMENTS}
    assert growth["forearm_l"] > 0.2
    assert all(abs(g) < 0.02 for k, g in growth.items() if k not in ("forearm_l", "trunk_limbs"))


# ------------------------------------------------------------------------------------------------ routes


def test_pages_and_subject_creation(station: tuple[TestClient, Any, str]) -> None:
    c, app, tok = station
    assert c.get("/healthz").json() == {"status": "ok"}
    assert "No subject yet" in c.get("/").text
    sid = _subject(c, tok)
    page = c.get(f"/subjects/{sid}")
    assert page.status_code == 200 and "P-001" in page.text and "No session yet" in page.text
    r = c.post("/subjects/find", data={"csrf_token": tok, "code": "P-001"}, follow_redirects=False)
    assert r.status_code == 303 and r.headers["location"] == f"/subjects/{sid}"
    rig_page = c.get("/rig")
    assert rig_page.status_code == 200 and ("none found" in rig_page.text or "serial" in rig_page.text)
    if "none found" in rig_page.text:  # no RealSense here: the live view says so
        r = c.get("/rig/alignment/front.jpg")
        assert r.status_code == 503 and "camera" in r.text
    assert c.get("/rig/alignment/side.jpg").status_code == 400
    assert "audit" in c.get("/audit").text.lower()
    assert c.get("/static/station.js").status_code == 200
    with app.state.factory() as db:
        actions = {e.action for e in db.scalars(select(AuditEvent))}
    assert {"create_subject", "view_subject"} <= actions


@pytest.mark.parametrize(("field", "value", "needle"), [
    ("code", "John Smith", "code"), ("code", "", "code"), ("sex", "x", "sex"), ("birth_year", "nineteen", "birth year"),
    ("birth_year", "1850", "birth year"), ("height_m", "175", "height"), ("mass_kg", "-3", "scale mass"),
])
def test_bad_subject_fields_are_refused(station: tuple[TestClient, Any, str], field: str, value: str,
                                        needle: str) -> None:
    c, app, tok = station
    data = {"csrf_token": tok, "code": "P-9", "sex": "male", field: value}
    r = c.post("/subjects", data=data)
    assert r.status_code in (400, 422) and needle in r.text
    assert _count(app, Subject) == 0


def test_duplicates_csrf_unknown_and_malformed_ids(station: tuple[TestClient, Any, str]) -> None:
    c, app, tok = station
    sid = _subject(c, tok)
    assert c.post("/subjects", data={"csrf_token": tok, "code": "P-001", "sex": "male"}).status_code == 409
    r = c.post("/subjects", data={"code": "P-002", "sex": "male"})
    assert r.status_code == 403 and "CSRF" in r.text
    r = c.post("/subjects", data={"csrf_token": "forged", "code": "P-002", "sex": "male"})
    assert r.status_code == 403
    assert _count(app, Subject) == 1
    for url in ("/subjects/999", "/sessions/999", "/jobs/999", "/results/999/files/report.html",
                f"/subjects/{sid}/compare?a=998&b=999", "/subjects/999/export.csv"):
        r = c.get(url)
        assert r.status_code == 404 and "does not exist" in r.text, url
    assert c.get("/api/jobs/999").json() == {"detail": "job 999 does not exist"}
    for url in ("/subjects/abc", "/sessions/1.5", "/api/jobs/x", f"/subjects/{sid}/compare?a=x&b=1"):
        r = c.get(url)
        assert r.status_code == 422 and "malformed request" in r.text, url
    r = c.post("/subjects/find", data={"csrf_token": tok, "code": "nobody"})
    assert r.status_code == 404 and "no subject" in r.text
    r = c.post("/sessions/999/process", data={"csrf_token": tok})
    assert r.status_code == 404
    assert _count(app, Job) == 0


def test_second_capture_while_one_runs_is_refused(station: tuple[TestClient, Any, str]) -> None:
    c, app, tok = station
    sid = _subject(c, tok)
    r = c.post(f"/subjects/{sid}/captures", data={"csrf_token": tok, "source": "virtual", "swollen": "forearm_l"},
               follow_redirects=False)
    assert r.status_code == 303 and re.fullmatch(r"/jobs/\d+", r.headers["location"])
    job = c.get("/api" + r.headers["location"]).json()
    assert job["state"] == "queued" and job["kind"] == "capture"
    assert "progress" in c.get(r.headers["location"]).text
    r = c.post(f"/subjects/{sid}/captures", data={"csrf_token": tok, "source": "virtual"})
    assert r.status_code == 409 and "already running" in r.text
    for bad, needle in (({"source": "webcam"}, "source"), ({"swollen": "nose"}, "swollen"),
                        ({"segmentation": "magic"}, "segmentation"), ({"index": "-1"}, "malformed"),
                        ({"source": "replay"}, "recording"), ({"source": "realsense", "segmentation": "oracle"}, "oracle")):
        r = c.post(f"/subjects/{sid}/captures", data={"csrf_token": tok, **bad})
        assert r.status_code in (400, 422) and needle in r.text, bad
    assert c.post("/subjects/999/captures", data={"csrf_token": tok}).status_code == 404
    assert c.post(f"/subjects/{sid}/previews", data={"csrf_token": tok}).status_code == 409  # the rig is busy
    assert _count(app, Job) == 1 and _count(app, Session) == 0


def _capture_zip(root: Path, drop: str | None = None) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for n in (*rig.CAPTURE_FILES, rig.CALIBRATION):
            if n != drop and (root / n).exists():
                zf.write(root / n, n)
    return buf.getvalue()


def test_uploads_that_are_not_captures_are_refused(station: tuple[TestClient, Any, str], tmp_path: Path) -> None:
    c, app, tok = station
    sid = _subject(c, tok)
    data_dir = app.state.config.data
    cases = [b"not a zip at all", _capture_zip(tmp_path)]
    fake = tmp_path / "fake"
    for cam in ("front", "back"):
        (fake / cam).mkdir(parents=True)
        (fake / cam / "color.png").write_bytes(b"png?")
        (fake / cam / "depth.png").write_bytes(b"png?")
        (fake / cam / "camera.json").write_text('{"intrinsics": {}, "depth_scale": 0.001}')
    (fake / "calibration.json").write_text("{}")
    cases.append(_capture_zip(fake))
    for blob in cases:
        r = c.post(f"/subjects/{sid}/uploads", data={"csrf_token": tok}, files={"file": ("c.zip", blob, "application/zip")})
        assert r.status_code == 400 and ("not a" in r.text or "missing" in r.text or "capture" in r.text), r.text
    assert _count(app, Session) == 0 and _count(app, Job) == 0
    assert not any((data_dir / "captures").iterdir()) and not any((data_dir / "tmp").iterdir())


def test_compare_export_session_and_result_files(station: tuple[TestClient, Any, str]) -> None:
    c, app, tok = station
    sid = _subject(c, tok)
    other = _subject(c, tok, "P-002")
    s1, s2 = _session(app, sid, _volumes(1.0)), _session(app, sid, _volumes(1.28))
    s3, s4 = _session(app, sid, None), _session(app, other, _volumes(1.0))
    page = c.get(f"/subjects/{sid}")
    assert "history-chart" in page.text and "repeatability table" in page.text and 'id="compare-form"' in page.text
    cmp = c.get(f"/subjects/{sid}/compare?a={s1}&b={s2}")
    assert cmp.status_code == 200
    flagged = re.findall(r'data-segment="(\w+)" data-significant="yes"', cmp.text)
    assert flagged == ["forearm_l"]
    assert "repeatability table" in cmp.text
    assert 'id="template-mismatch"' not in cmp.text
    assert c.get(f"/subjects/{sid}/compare?a={s1}&b={s3}").status_code == 409
    assert c.get(f"/subjects/{sid}/compare?a={s1}&b={s4}").status_code == 404
    csv_text = c.get(f"/subjects/{sid}/export.csv").text.splitlines()
    assert csv_text[0].startswith("subject_code,session_id") and len(csv_text) == 3
    assert csv_text[2].split(",")[0] == "P-001" and "1.2800" in csv_text[2]
    pdf = c.get(f"/subjects/{sid}/export.pdf")
    assert pdf.status_code == 200 and pdf.content.startswith(b"%PDF")
    ses = c.get(f"/sessions/{s1}")
    assert ses.status_code == 200 and "forearm_l" in ses.text and "repeatability table" in ses.text
    for name, code in (("..%2Fstation.sqlite3", 404), ("report.exe", 400), ("report.html", 404)):
        assert c.get(f"/results/1/files/{name}").status_code in (code, 400, 404)
    r = c.post(f"/sessions/{s1}/process", data={"csrf_token": tok, "segmentation": "oracle"}, follow_redirects=False)
    assert r.status_code == 303
    assert c.post(f"/sessions/{s1}/process", data={"csrf_token": tok, "segmentation": "x"}).status_code == 400
    with app.state.factory() as db:
        actions = [e.action for e in db.scalars(select(AuditEvent))]
    assert {"view_compare", "export_csv", "export_pdf", "view_session", "queue_process"} <= set(actions)
    # results fitted with different templates are flagged (a result without the record: the average one)
    s5 = _session(app, sid, {**_volumes(1.0), "template": {"kind": "female", "sex": "female"}})
    mixed = c.get(f"/subjects/{sid}/compare?a={s1}&b={s5}").text
    assert 'id="template-mismatch"' in mixed and "default → female" in mixed


def test_history_shows_the_template_of_every_result(station: tuple[TestClient, Any, str],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """The CSV's template column, the subject page's and the PDF's template per result and the chart's
    change marks: a result without the ``template`` record was fitted with the average ("default") one."""
    import csv

    c, app, tok = station
    sid = _subject(c, tok)
    female = {**_volumes(1.1), "template": {"kind": "female", "sex": "female"}}
    s1, s2 = _session(app, sid, _volumes(1.0)), _session(app, sid, female)
    _session(app, sid, None)  # no result: no template, left out of the chart's change marks
    s4 = _session(app, sid, {**_volumes(1.2), "template": {"kind": "custom", "sex": None}})
    text = c.get(f"/subjects/{sid}/export.csv").text
    head, rows = next(csv.reader(io.StringIO(text))), list(csv.DictReader(io.StringIO(text)))
    assert head[6:9] == ["software_version", "template", "operator"] and head[9] == "interval_source"
    assert [(int(r["session_id"]), r["template"]) for r in rows] == [(s1, "default"), (s2, "female"), (s4, "custom")]
    assert all(r["operator"] == "local" and r["software_version"] == "t" for r in rows)
    page = c.get(f"/subjects/{sid}").text
    assert re.findall(r'data-template="(\w+)"', page) == ["default", "female", "custom"]
    assert page.count("(changed)") == 2 and 'id="template-change"' in page and "Dashed line" in page
    weasyprint = pytest.importorskip("weasyprint")
    rendered: list[str] = []
    real_html = weasyprint.HTML

    def html(string: str) -> Any:  # the PDF's HTML, kept to be read here
        rendered.append(string)
        return real_html(string=string)

    monkeypatch.setattr(weasyprint, "HTML", html)
    pdf = c.get(f"/subjects/{sid}/export.pdf")
    assert pdf.status_code == 200 and pdf.content.startswith(b"%PDF")
    assert re.search(r"<td>template</td><td>default</td><td>female \(changed\)</td><td>custom \(changed\)</td>",
                     rendered[0])
    # one template throughout: no change marked
    other = _subject(c, tok, "P-002")
    for vols in (_volumes(1.0), {**_volumes(1.0), "template": {"kind": "default", "sex": None}}):
        _session(app, other, vols)
    plain = c.get(f"/subjects/{other}").text
    assert re.findall(r'data-template="(\w+)"', plain) == ["default", "default"]
    assert "(changed)" not in plain and 'id="template-change"' not in plain


def test_template_kind_and_change_points() -> None:
    from bsv.station.charts import history_png, result_template_kind, template_changes

    assert result_template_kind(_volumes(1.0)) == "default"  # before the sexed templates: the average one
    assert result_template_kind({"template": {"kind": "male", "sex": "male"}}) == "male"
    assert result_template_kind({"template": {"kind": None, "sex": None}}) == "default"
    assert result_template_kind({"template": None}) == "default"
    assert template_changes([]) == [] and template_changes(["default"]) == []
    assert template_changes(["default", "default", "female", "female", "male", "default"]) == [2, 4, 5]
    vols = [_volumes(1.0), {**_volumes(1.1), "template": {"kind": "female", "sex": "female"}},
            {**_volumes(1.2), "template": {"kind": "female", "sex": "female"}}, _volumes(1.3)]
    assert template_changes([result_template_kind(v) for v in vols]) == [1, 3]
    for labels, v in ((["#1", "#2", "#3", "#4"], vols), (["#1"], vols[1:2])):
        url = history_png(labels, v)
        assert url.startswith("data:image/png;base64,") and len(url) > 1000


def test_login_roles_and_csrf_off_localhost(tmp_path: Path) -> None:
    from bsv.station.security import add_user

    app = create_app(_config(tmp_path / "d", host="0.0.0.0", run_jobs=False))
    with app.state.factory() as db:
        add_user(db, "olga", "correct horse battery", "operator")
        add_user(db, "vic", "viewer password 1", "viewer")
        with pytest.raises(ValueError, match="at least 10"):
            add_user(db, "x", "short", "viewer")
    with TestClient(app) as c:
        r = c.get("/", follow_redirects=False)
        assert r.status_code == 303 and r.headers["location"] == "/login"
        assert c.get("/api/jobs/1").status_code == 401
        tok = _token(c)
        r = c.post("/login", data={"csrf_token": tok, "name": "olga", "password": "wrong"})
        assert r.status_code == 401 and "wrong user name or password" in r.text
        assert c.post("/login", data={"name": "olga", "password": "correct horse battery"}).status_code == 403
        r = c.post("/login", data={"csrf_token": tok, "name": "olga", "password": "correct horse battery"},
                   follow_redirects=False)
        assert r.status_code == 303
        home = c.get("/")
        assert home.status_code == 200
        assert tok not in home.text  # the CSRF token is renewed at login
        tok = TOKEN.search(home.text).group(1)  # type: ignore[union-attr]
        _subject(c, tok)
        assert c.post("/logout", data={"csrf_token": tok}, follow_redirects=False).status_code == 303
        assert c.get("/", follow_redirects=False).status_code == 303
        tok = _token(c)
        c.post("/login", data={"csrf_token": tok, "name": "vic", "password": "viewer password 1"})
        viewed = c.get("/subjects/1")
        assert viewed.status_code == 200
        tok = TOKEN.search(viewed.text).group(1)  # type: ignore[union-attr]
        r = c.post("/subjects", data={"csrf_token": tok, "code": "P-3", "sex": "male"})
        assert r.status_code == 403 and "operator" in r.text
        assert c.get("/audit").status_code == 403
    with app.state.factory() as db:
        users = {(e.user, e.action) for e in db.scalars(select(AuditEvent))}
        stored = db.scalars(select(Subject)).one()
    assert ("olga", "login") in users and ("?", "login_failed") in users and ("vic", "view_subject") in users
    assert stored.code == "P-001"
    from bsv.station.models import User

    with app.state.factory() as db:
        assert all(u.password_hash.startswith("$argon2id$") for u in db.scalars(select(User)))


def test_backup_archives_database_and_refuses_to_overwrite(station: tuple[TestClient, Any, str], tmp_path: Path) -> None:
    import json

    from bsv.errors import OutputExistsError
    from bsv.station.backup import backup

    c, app, tok = station
    _subject(c, tok)
    config = app.state.config
    out = backup(config.data, tmp_path / "b" / "station.tar.gz", config.db_url)
    with tarfile.open(out) as tar:
        assert ("station.sqlite3" in tar.getnames()) == (config.db_url is None)
        tables = json.load(tar.extractfile("tables.json"))  # type: ignore[arg-type]
    assert [s["code"] for s in tables["subjects"]] == ["P-001"]
    assert {e["action"] for e in tables["audit"]} == {"create_subject"}
    with pytest.raises(OutputExistsError):
        backup(config.data, out, config.db_url)


# ------------------------------------------------------------------------------------------------ jobs


def _wait(c: TestClient, job: str, timeout: float = 240.0) -> dict[str, Any]:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        j: dict[str, Any] = c.get(f"/api/jobs/{job}").json()
        if j["state"] in ("done", "failed"):
            return j
        time.sleep(0.5)
    raise AssertionError(f"job {job} did not finish in {timeout} s")


@pytest.mark.slow
def test_virtual_rig_job_then_a_failing_job_keeps_the_history(tmp_path: Path) -> None:
    app = create_app(_config(tmp_path / "data"))
    with TestClient(app) as c:
        tok = _token(c)
        sid = _subject(c, tok)
        # preview and pose check (MediaPipe) first: no session is made
        r = c.post(f"/subjects/{sid}/previews", data={"csrf_token": tok, "source": "virtual"}, follow_redirects=False)
        preview = _wait(c, r.headers["location"].rsplit("/", 1)[1])
        assert preview["state"] == "done" and preview["message"] == "", preview
        page = c.get(r.headers["location"]).text
        assert 'id="a-pose">A-pose<' in page and "capture-now" in page
        for name in ("color.png", "segmentation.png"):
            assert c.get(f"{r.headers['location']}/preview/back/{name}").content.startswith(b"\x89PNG")
        assert _count(app, Session) == 0
        r = c.post(f"/subjects/{sid}/captures", data={"csrf_token": tok, "source": "virtual", "segmentation": "oracle"},
                   follow_redirects=False)
        job = _wait(c, r.headers["location"].rsplit("/", 1)[1])
        assert job["state"] == "done", job
        vols = c.get(f"/results/{job['result_id']}/files/volumes.json").json()
        assert c.get(f"/results/{job['result_id']}/files/report.pdf").content.startswith(b"%PDF-")  # the handover copy
        assert c.get(f"/results/{job['result_id']}/files/volumes.csv").text.startswith("segment,")
        truth = rig.virtual_body(0, 0, None)[1]
        assert abs(vols["volumes_l"]["trunk_limbs"] / truth["trunk_limbs"] - 1) < 0.05
        assert c.get(f"/results/{job['result_id']}/files/report.html").status_code == 200
        assert len(list((tmp_path / "data" / "charts").iterdir())) == 1  # drawn by the worker
        ses_page = c.get(f"/sessions/{job['session_id']}")
        assert ses_page.status_code == 200 and "front colour" in ses_page.text
        png = c.get(f"/sessions/{job['session_id']}/capture/front/color.png")
        assert png.status_code == 200 and png.content.startswith(b"\x89PNG")
        assert c.get(f"/sessions/{job['session_id']}/capture/side/color.png").status_code == 400
        # oracle segmentation writes no MediaPipe overlay
        assert c.get(f"/results/{job['result_id']}/segmentation/front/segmentation.png").status_code == 404
        # a replay without a station calibration fails in the worker: the page shows the pipeline's message
        r = c.post(f"/subjects/{sid}/captures", data={"csrf_token": tok, "source": "replay", "recording_dir": "/nowhere"},
                   follow_redirects=False)
        failed = _wait(c, r.headers["location"].rsplit("/", 1)[1])
        assert failed["state"] == "failed" and "no station calibration" in failed["message"]
        page = c.get(f"/subjects/{sid}").text
        assert "no station calibration" in page and "Traceback" not in page
    with app.state.factory() as db:
        sessions = db.scalars(select(Session)).all()
        assert len(sessions) == 1 and len(sessions[0].results) == 1
    assert not any((tmp_path / "data" / "tmp").iterdir()) if (tmp_path / "data" / "tmp").exists() else True


def test_demo_seeds_a_sample_subject_and_a_virtual_session_once(tmp_path: Path) -> None:
    config = _config(tmp_path / "demo", demo=True, run_jobs=False)
    for _ in range(2):  # a second start adds nothing
        app = create_app(config)
        with TestClient(app) as c:
            assert "DEMO-001" in c.get("/").text
    assert _count(app, Subject) == 1 and _count(app, Job) == 1
    with app.state.factory() as db:
        job = db.scalars(select(Job)).one()
    assert job.kind == "capture" and job.params["source"] == "virtual" and job.state == "queued"


def test_cli_routes_station(capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from bsv.cli import main

    with pytest.raises(SystemExit) as e:
        main(["station", "--help"])
    assert e.value.code == 0 and "--demo" in capsys.readouterr().out
    assert main(["station", "--host", "0.0.0.0", "--data", str(tmp_path / "d")]) == 2
    assert "adduser" in capsys.readouterr().err
    monkeypatch.setenv("BSV_STATION_PASSWORD", "a long enough password")
    assert main(["station", "adduser", "olga", "--role", "operator", "--data", str(tmp_path / "d")]) == 0
    assert main(["station", "adduser", "olga", "--role", "operator", "--data", str(tmp_path / "d")]) == 2
    out = tmp_path / "backup.tar.gz"
    assert main(["station", "backup", str(out), "--data", str(tmp_path / "d")]) == 0 and out.is_file()


def test_pose_check_reads_the_landmarks(tmp_path: Path) -> None:
    import json

    from bsv.frontend.segment import REQUIRED_LANDMARKS
    from bsv.station.posecheck import pose_check

    assert pose_check(tmp_path) is None
    lm = {n: [0.0, 0.0, 0.99] for n in REQUIRED_LANDMARKS}
    # front view, image y down: shoulders at y=100, hips at y=300; left wrist 40 deg out, right wrist 80 deg out
    lm.update(left_shoulder=[120, 100, 0.99], right_shoulder=[80, 100, 0.99], left_hip=[110, 300, 0.99],
              right_hip=[90, 300, 0.99], left_wrist=[120 + 100 * math.sin(math.radians(40)), 100 + 100 * math.cos(math.radians(40)), 0.99],
              right_wrist=[80 - 100 * math.sin(math.radians(80)), 100 + 100 * math.cos(math.radians(80)), 0.5])
    (tmp_path / "segmentation" / "front").mkdir(parents=True)
    (tmp_path / "segmentation" / "front" / "landmarks.json").write_text(json.dumps({"landmarks_px": lm}))
    front = pose_check(tmp_path)["cameras"]["front"]  # type: ignore[index]
    assert front["abduction_deg"]["left"] == pytest.approx(40.0, abs=0.01)
    assert front["abduction_deg"]["right"] == pytest.approx(80.0, abs=0.01)
    assert front["a_pose"] is False and front["low"] == ["right_wrist"]

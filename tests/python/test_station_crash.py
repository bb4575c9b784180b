"""Crash safety: kill -9 the station while it writes (subjects being created by several clients, a
virtual-rig job running in the worker), restart it, and check that SQLite's integrity check passes,
every acknowledged write is there, the interrupted job is marked as such and no half-written file or
row is left."""

from __future__ import annotations

import re
import sqlite3
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("fastapi", reason="BSV Station needs requirements-station.txt (scripts/setup.sh installs it)")

import httpx
from station_server import Server

TOKEN = re.compile(r'name="csrf_token" value="([^"]+)"')


def _client(url: str) -> tuple[httpx.Client, str]:
    c = httpx.Client(base_url=url, timeout=10.0)
    m = TOKEN.search(c.get("/").text)
    assert m is not None
    return c, m.group(1)


def _writer(url: str, prefix: str, acked: list[str], stop: threading.Event) -> None:
    try:
        c, tok = _client(url)
        i = 0
        while not stop.is_set():
            code = f"{prefix}-{i}"
            r = c.post("/subjects", data={"csrf_token": tok, "code": code, "sex": "male"})
            if r.status_code == 303:
                acked.append(code)
            i += 1
    except httpx.HTTPError:
        return  # the server died under us


@pytest.mark.slow
@pytest.mark.parametrize("kill_in", ["capturing", "processing"])
def test_kill9_during_writes_keeps_the_database_whole(tmp_path: Path, kill_in: str) -> None:
    data = tmp_path / "data"
    server = Server(data).start()
    acked: list[str] = []
    stop = threading.Event()
    threads = [threading.Thread(target=_writer, args=(server.url, f"W{k}", acked, stop), daemon=True)
               for k in range(4)]
    try:
        c, tok = _client(server.url)
        r = c.post("/subjects", data={"csrf_token": tok, "code": "JOB-1", "sex": "female"})
        sid = int(r.headers["location"].rsplit("/", 1)[1])
        r = c.post(f"/subjects/{sid}/captures", data={"csrf_token": tok, "source": "virtual", "segmentation": "oracle"})
        job = int(r.headers["location"].rsplit("/", 1)[1])
        for t in threads:
            t.start()
        t0 = time.monotonic()
        while c.get(f"/api/jobs/{job}").json()["state"] != kill_in and time.monotonic() - t0 < 120:
            time.sleep(0.1)
        time.sleep(0.5)
        state_before = c.get(f"/api/jobs/{job}").json()["state"]
        assert state_before == kill_in
        print(f"\nkilled while the job was {state_before}: {len(acked)} subjects acknowledged")
        server.kill9()
    finally:  # a failure above must not leave the station and its writers running (pytest would wait for them)
        stop.set()
        server.stop()
        for t in threads:
            if t.is_alive():
                t.join(15)
    time.sleep(1.0)  # the worker notices its parent is gone and exits
    db = data / "station.sqlite3"
    with sqlite3.connect(db) as conn:
        assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    restarted = Server(data).start()
    try:
        with sqlite3.connect(db) as conn:
            assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
            codes = {row[0] for row in conn.execute("SELECT code FROM subjects")}
            sessions = conn.execute("SELECT capture_dir FROM sessions").fetchall()
            results = conn.execute("SELECT report_dir FROM results").fetchall()
        assert len(acked) > 10
        assert set(acked) <= codes, "an acknowledged subject is missing after the crash"
        for (folder,) in sessions:
            assert (data / folder / "front" / "color.png").is_file() and (data / folder / "calibration.json").is_file()
        for (folder,) in results:
            assert (data / folder / "volumes.json").is_file()
        j = httpx.get(f"{restarted.url}/api/jobs/{job}").json()
        assert j["state"] == "failed" and "interrupted" in j["message"]
        assert not (data / "tmp").exists() or not any((data / "tmp").iterdir())
        page = httpx.get(f"{restarted.url}/subjects/{sid}")
        assert page.status_code == 200
    finally:
        restarted.stop()

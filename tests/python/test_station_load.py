"""Load test on loopback: uvicorn in a subprocess, 20 concurrent clients browsing every page while 3
processing jobs run from the queue; bounded in time. No request may fail, no job or result be lost;
p95 page latency and the job throughput are printed and written to tests/artifacts/station/load.json."""

from __future__ import annotations

import json
import re
import statistics
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("fastapi", reason="BSV Station needs requirements-station.txt (scripts/setup.sh installs it)")

import httpx
from station_server import ARTIFACTS, Server

TOKEN = re.compile(r'name="csrf_token" value="([^"]+)"')
CLIENTS, JOBS, BOUND_S = 20, 3, 300.0


def _wait(c: httpx.Client, job: int, timeout: float) -> dict:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        j: dict = c.get(f"/api/jobs/{job}").json()
        if j["state"] in ("done", "failed"):
            return j
        time.sleep(0.5)
    raise AssertionError(f"job {job} not finished in {timeout} s")


@pytest.mark.slow
def test_twenty_clients_browse_while_three_jobs_run(tmp_path: Path) -> None:
    server = Server(tmp_path / "data").start()
    try:
        c = httpx.Client(base_url=server.url, timeout=30.0)
        tok = TOKEN.search(c.get("/").text).group(1)  # type: ignore[union-attr]
        sid = int(c.post("/subjects", data={"csrf_token": tok, "code": "LOAD-1", "sex": "male"})
                  .headers["location"].rsplit("/", 1)[1])
        r = c.post(f"/subjects/{sid}/captures", data={"csrf_token": tok, "source": "virtual", "segmentation": "oracle"})
        first = _wait(c, int(r.headers["location"].rsplit("/", 1)[1]), 240)
        assert first["state"] == "done", first
        ses, rid = first["session_id"], first["result_id"]
        # the subject's recorded sex reaches the process (an oracle job: the cloud's labels, the average template)
        assert c.get(f"/results/{rid}/files/volumes.json").json()["template"] == {"kind": "default", "sex": "male"}
        t_queue = time.monotonic()
        jobs = [int(c.post(f"/sessions/{ses}/process", data={"csrf_token": tok, "segmentation": "oracle"})
                    .headers["location"].rsplit("/", 1)[1]) for _ in range(JOBS)]
        pages = ["/", f"/subjects/{sid}", f"/sessions/{ses}", f"/api/jobs/{jobs[-1]}",
                 f"/results/{rid}/files/report.html", f"/subjects/{sid}/export.csv", "/rig", f"/jobs/{jobs[0]}"]
        lat: list[float] = []
        per_url: dict[str, list[float]] = {u: [] for u in pages}
        errors: list[str] = []
        done = threading.Event()
        finished: dict[int, float] = {}

        def browse(k: int) -> None:
            with httpx.Client(base_url=server.url, timeout=30.0) as cl:
                i = k
                while not done.is_set():
                    url = pages[i % len(pages)]
                    t = time.perf_counter()
                    try:
                        resp = cl.get(url)
                        if resp.status_code != 200:
                            errors.append(f"{url}: {resp.status_code}")
                    except httpx.HTTPError as e:
                        errors.append(f"{url}: {type(e).__name__}")
                    lat.append(time.perf_counter() - t)
                    per_url[url].append(lat[-1])
                    i += 1

        threads = [threading.Thread(target=browse, args=(k,)) for k in range(CLIENTS)]
        for t in threads:
            t.start()
        try:
            while len(finished) < JOBS and time.monotonic() - t_queue < BOUND_S:
                for j in jobs:
                    if j not in finished and c.get(f"/api/jobs/{j}").json()["state"] in ("done", "failed"):
                        finished[j] = time.monotonic() - t_queue
                time.sleep(0.5)
        finally:
            done.set()
            for t in threads:
                t.join(60)
        states = [c.get(f"/api/jobs/{j}").json()["state"] for j in jobs]
        page = c.get(f"/sessions/{ses}").text
        elapsed = max(finished.values()) if finished else float("nan")
        lat.sort()
        stats = {"clients": CLIENTS, "jobs": JOBS, "requests": len(lat), "failed_requests": len(errors),
                 "p50_ms": 1e3 * statistics.median(lat), "p95_ms": 1e3 * lat[int(0.95 * (len(lat) - 1))],
                 "max_ms": 1e3 * lat[-1], "jobs_wall_s": elapsed, "jobs_per_min": 60.0 * JOBS / elapsed,
                 "requests_per_s": len(lat) / elapsed,
                 "max_ms_per_page": {re.sub(r"\d+", "N", u): round(1e3 * max(v), 1) for u, v in per_url.items() if v}}
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        (ARTIFACTS / "load.json").write_text(json.dumps(stats, indent=2) + "\n")
        print("\n" + json.dumps(stats, indent=2))
        assert states == ["done"] * JOBS, states
        assert not errors, errors[:10]
        assert page.count("/files/report.html") == 1 + JOBS  # every result is kept, none overwritten
        assert stats["p95_ms"] < 5000
    finally:
        server.stop()
    assert "LOAD-1" not in server.log.read_text()  # no subject code in the server's log

"""bsv batch on Dask distributed: 12 inputs (9 labelled clouds + 1 capture folder of the virtual rig + 2
corrupt files) on a 2-worker LocalCluster; failures recorded, table complete, a killed worker's task
re-run, a second run skipping everything, timeouts, manifests and refused calls."""

from __future__ import annotations

import json
import os
import signal
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("distributed", reason="bsv batch needs dask[distributed] (requirements-batch.txt)")
pytest.importorskip("pyarrow", reason="bsv batch needs pyarrow (requirements-batch.txt)")

import bsv
from bsv.batch.items import collect_items
from bsv.batch.main import main as batch_main
from bsv.batch.runner import run_batch
from bsv.batch.state import JOURNAL, Spec, load_journal
from bsv.batch.table import read_table

#: A short registration schedule (the test is about the batch): on these virtual scans (every 4th point)
#: it lands the trunk-and-limb volume within about 1 % of the truth.
SCHEDULE = "m2p:5,p2m:5"
FAST = ["--param", f"schedule={SCHEDULE}"]
GOOD = [f"scan_{i}" for i in range(9)] + ["capture"]
BAD = ["truncated", "garbage"]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Nine labelled virtual scans of one cohort subject (different scan seeds, l515 noise), one capture
    folder of the virtual rig (images + calibration.json), a truncated PLY and a file that is no PLY."""
    from bsv.bodies import subject

    root = tmp_path_factory.mktemp("batch_inputs")
    s = subject(1, 0, local=False)
    mesh = s.body.mesh()
    paths = []
    for i in range(9):
        p = root / f"scan_{i}.ply"
        c = bsv.scan(mesh, "l515", i)
        bsv.write_point_cloud(p, c.points[::4], labels=c.labels[::4])
        paths.append(p)
    bsv.scan(mesh, "noer", 99, images=root / "capture")
    good = paths[0].read_bytes()
    (root / "truncated.ply").write_bytes(good[: len(good) // 2])
    (root / "garbage.ply").write_bytes(b"this is not a point cloud\n")
    ins = [*paths, root / "capture", root / "truncated.ply", root / "garbage.ply"]
    return {"root": root, "inputs": [str(p) for p in ins], "truth": s.volumes_l()}


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    """A 2-worker LocalCluster (one thread per worker) shared by the tests that pass a client."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as c:
        yield c


def _cli(inputs: list[str], out: Path, *extra: str) -> int:
    return batch_main([*inputs, "--out", str(out), "--workers", "2", "--segmentation", "oracle", "--quiet",
                       "--no-dashboard", *FAST, *extra])


def _check_complete(out: Path, truth: dict[str, float]) -> None:
    """10 item folders with their outputs, none for the corrupt inputs, the table complete and right."""
    import pyarrow.csv as pcsv

    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == sorted(GOOD)  # no leftover .tmp-* folder
    for name in GOOD:
        assert (out / name / "fitted.ply").is_file() and (out / name / "volumes.json").is_file()
    assert (out / "capture" / "report.html").is_file()  # capture items get bsv process's outputs
    t = read_table(out).to_pylist()
    csv_rows = pcsv.read_csv(out / "results.csv").num_rows
    assert csv_rows == len(t)
    failed = {r["item"]: r for r in t if r["status"] == "failed"}
    assert set(failed) == set(BAD)
    assert all(r["segment"] is None and r["error_type"] == "FormatError" and r["error"] for r in failed.values())
    assert "garbage.ply" in failed["garbage"]["error"] and "truncated.ply" in failed["truncated"]["error"]
    ok = [r for r in t if r["status"] == "ok"]
    assert {r["item"] for r in ok} == set(GOOD)
    tl = {r["item"]: r["volume_l"] for r in ok if r["segment"] == "trunk_limbs"}
    assert len(tl) == 10
    for name, v in tl.items():  # ground truth: the scanned subject's trunk-and-limb volume
        assert abs(v - truth["trunk_limbs"]) / truth["trunk_limbs"] < 0.04, (name, v, truth["trunk_limbs"])
    segs = {r["segment"] for r in ok}
    assert {"torso", "thigh_l", "shin_r", "upper_arm_l", "forearm_r", "trunk_limbs"} <= segs
    assert all(r["seconds"] > 0 and r["rms_mesh_to_points_mm"] is not None for r in ok)
    assert len(load_journal(out)) == 12


def test_twelve_inputs_two_corrupt_a_killed_worker_then_a_second_run_skips_everything(
        inputs: dict[str, Any], tmp_path: Path) -> None:
    """A 2-worker LocalCluster over 12 inputs, 2 corrupt; the worker running the second task to start is
    SIGKILLed right after it started: its nanny restarts it, the scheduler runs the task again, every good
    item finishes. Then the same command skips everything and still exits 1 (two recorded failures)."""
    out = tmp_path / "batch"
    killed: list[dict[str, Any]] = []
    seen: list[str] = []
    lock = threading.Lock()

    def kill_second_task(msg: dict[str, Any]) -> None:
        with lock:
            if killed or msg["item"] in BAD:
                return
            if seen:
                killed.append(msg)
                os.kill(int(msg["pid"]), signal.SIGKILL)
            seen.append(msg["item"])

    items = collect_items(inputs["inputs"])
    spec = Spec(segmentation="oracle", params={"schedule": SCHEDULE})
    res = run_batch(items, out, spec, workers=2, progress=False, dashboard=False, on_start=kill_second_task)
    assert killed, "no task started"
    victim = killed[0]["item"]
    assert res.attempts[victim] >= 2  # the killed task ran again on a (restarted or other) worker
    assert sorted(res.done) == sorted(GOOD) and sorted(res.failed) == sorted(BAD) and res.exit_code == 1
    _check_complete(out, inputs["truth"])
    rows = [r for r in read_table(out).to_pylist() if r["item"] == victim]
    assert rows and all(r["attempts"] >= 2 for r in rows)

    mtimes = {n: (out / n / "item.json").stat().st_mtime_ns for n in GOOD}
    lines = (out / JOURNAL).read_text().count("\n")
    assert _cli(inputs["inputs"], out) == 1  # the same command: nothing runs, two failures on record
    assert {n: (out / n / "item.json").stat().st_mtime_ns for n in GOOD} == mtimes
    assert (out / JOURNAL).read_text().count("\n") == lines
    _check_complete(out, inputs["truth"])
    assert Spec(segmentation="oracle", params={"schedule": "m2p:4"}).key() != spec.key()  # other parameters: new


def test_rerun_failed_and_changed_input(inputs: dict[str, Any], client: Any, tmp_path: Path) -> None:
    root = tmp_path / "in"
    root.mkdir()
    src = Path(inputs["inputs"][0])
    (root / "a.ply").write_bytes(src.read_bytes())
    (root / "b.ply").write_bytes(b"not a ply\n")
    out = tmp_path / "batch"
    items = collect_items([root / "a.ply", root / "b.ply"])
    spec = Spec(params={"schedule": SCHEDULE})

    def run(rerun_failed: bool = False) -> int:
        return run_batch(items, out, spec, client=client, rerun_failed=rerun_failed, progress=False).exit_code

    assert run() == 1
    assert run() == 1 and len((out / JOURNAL).read_text().splitlines()) == 2  # nothing re-run
    assert run(rerun_failed=True) == 1
    recs = [json.loads(x) for x in (out / JOURNAL).read_text().splitlines()]
    assert sorted(r["item"] for r in recs[:2]) == ["a", "b"] and recs[2]["item"] == "b"  # only b ran again
    (root / "b.ply").write_bytes(src.read_bytes())  # the input is fixed: its hash changes, it runs again
    assert run() == 0
    assert (out / "b").is_dir()
    t = read_table(out).to_pylist()
    assert {r["status"] for r in t} == {"ok"} and {r["item"] for r in t} == {"a", "b"}
    # New parameters that fail: every item runs again, is recorded failed with the typed error naming the
    # parameter, and the folders of the older results go (DIR/<item>/ exists only for a current success).
    bad = Spec(params={"schedule": SCHEDULE, "alpha": -1.0})
    assert run_batch(items, out, bad, client=client, progress=False).exit_code == 1
    t = read_table(out).to_pylist()
    assert {r["error_type"] for r in t} == {"RegistrationParameterError"} and all("alpha" in r["error"] for r in t)
    assert not (out / "a").exists() and not (out / "b").exists()


def test_a_task_past_the_timeout_is_cancelled_and_recorded(inputs: dict[str, Any], client: Any,
                                                           tmp_path: Path) -> None:
    items = collect_items(inputs["inputs"][:2])
    pids = set(client.run(os.getpid).values())
    # 400 iterations (no convergence stop) take far longer than 1 s: the item is cancelled and its worker
    # process restarted.
    res = run_batch(items[:1], tmp_path / "slow", Spec(params={"schedule": "m2p:400", "stop_motion_mm": 0}),
                    client=client,
                    timeout=1.0, progress=False)
    assert res.exit_code == 1
    rec = res.records[items[0].name]
    assert rec["error_type"] == "TimeoutError" and "--timeout 1" in rec["error"]
    assert not (tmp_path / "slow" / items[0].name).exists()
    assert len(set(client.run(os.getpid).values()) - pids) == 1  # the computation was stopped with its process
    # The cluster goes on with the next batch.
    ok = run_batch(items[1:], tmp_path / "next", Spec(what="report", params={"schedule": SCHEDULE}), client=client,
                   progress=False)
    assert ok.exit_code == 0 and ok.done == [items[1].name]
    assert (tmp_path / "next" / items[1].name / "report.html").is_file()  # --what report on a cloud item


def test_manifest_names_and_refused_calls(inputs: dict[str, Any], tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    src = Path(inputs["inputs"][0])
    man = tmp_path / "study.csv"
    man.write_text(f"path,name\n{src},subject-A\n{src.name},subject B\n")
    (tmp_path / src.name).write_bytes(src.read_bytes())  # relative to the manifest's folder
    items = collect_items([man])
    assert [(i.name, i.kind) for i in items] == [("subject-A", "cloud"), ("subject_B", "cloud")]

    dup = tmp_path / "dup.csv"
    dup.write_text(f"path\n{src}\n{src}\n")
    assert batch_main([str(dup), "--out", str(tmp_path / "o1"), "--quiet"]) == 2
    assert "would both write" in capsys.readouterr().err
    nopath = tmp_path / "nopath.csv"
    nopath.write_text("file\nx.ply\n")
    assert batch_main([str(nopath), "--out", str(tmp_path / "o2"), "--quiet"]) == 2
    assert "no 'path' column" in capsys.readouterr().err
    assert batch_main([str(tmp_path / "missing.ply"), "--out", str(tmp_path / "o3"), "--quiet"]) == 2
    assert "does not exist" in capsys.readouterr().err
    other = tmp_path / "someone_elses"
    other.mkdir()
    (other / "notes.txt").write_text("keep me")
    assert batch_main([str(src), "--out", str(other), "--quiet"]) == 2
    assert "not a batch folder" in capsys.readouterr().err
    assert (other / "notes.txt").read_text() == "keep me"
    assert batch_main([str(src), "--out", str(tmp_path / "o4"), "--scheduler", "nowhere", "--quiet"]) == 2
    assert batch_main([str(src), "--out", str(tmp_path / "o5"), "--workers", "0", "--quiet"]) == 2
    assert not [i for i in range(1, 6) if (tmp_path / f"o{i}").exists()]  # a refused call writes nothing


def test_bench_synth_on_a_running_scheduler_gives_the_sequential_numbers(client: Any) -> None:
    """``bsv bench synth --scheduler tcp://...``: the subjects run as tasks on a running scheduler (this
    module's cluster) and give bit-for-bit the numbers of the in-process run (the registration is
    deterministic)."""
    from bsv.bench.synth import SynthConfig, run_synth

    cfg = SynthConfig(n=1, conditions=("noer",), params={"schedule": SCHEDULE}, local=False)
    infos_seq, runs_seq, _ = run_synth(cfg, progress=False)
    infos_dask, runs_dask, _ = run_synth(cfg, progress=False, scheduler=client.scheduler.address)
    assert client.scheduler.address.startswith("tcp://")
    assert [r.subject for r in runs_dask] == [r.subject for r in runs_seq] == ["subject_000"]
    assert all(r.ok for r in runs_dask)
    assert [r.estimated_l for r in runs_dask] == [r.estimated_l for r in runs_seq]
    assert [i["subject"] for i in infos_dask] == [i["subject"] for i in infos_seq]


def test_an_interrupted_batch_continues_where_it_stopped(inputs: dict[str, Any], client: Any, tmp_path: Path) -> None:
    """Ctrl-C (SIGINT) once the first item is in the journal: exit 130, a readable table of the finished
    items, no temporary folder; the same batch then runs only the rest."""
    import subprocess
    import sys
    import time

    ins = inputs["inputs"][:4]
    out = tmp_path / "batch"
    proc = subprocess.Popen([sys.executable, "-m", "bsv.cli", "batch", *ins, "--out", str(out), "--workers", "1",
                             "--segmentation", "oracle", "--quiet", "--no-dashboard", *FAST],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None:
        if (out / JOURNAL).is_file() and (out / JOURNAL).read_text().count("\n") >= 1:
            break
        time.sleep(0.1)
    assert proc.poll() is None, "the batch ended before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err.decode()[-2000:]
    done = load_journal(out)
    assert 1 <= len(done) < 4
    assert {r["item"] for r in read_table(out).to_pylist()} == set(done)
    assert not list(out.glob(".tmp-*"))
    # Item folders are complete: the journaled ones, and maybe one finished while the client was stopping
    # (its item.json makes the next run adopt it).
    folders = {p.name for p in out.iterdir() if p.is_dir()}
    assert set(done) <= folders and all((out / n / "item.json").is_file() for n in folders)
    res = run_batch(collect_items(ins), out, Spec(segmentation="oracle", params={"schedule": SCHEDULE}),
                    client=client, progress=False)
    assert (res.ran, res.skipped, res.exit_code) == (4 - len(folders), len(folders), 0)
    assert len(load_journal(out)) == 4
    assert {r["item"] for r in read_table(out).to_pylist() if r["segment"] == "trunk_limbs"} == set(res.done)
    assert sorted(res.done) == sorted(Path(p).stem for p in ins)


def test_the_dashboard_line_gives_the_address_or_how_to_turn_it_on(client: Any,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    from bsv.batch import cluster

    class WithLink:
        dashboard_link = "http://127.0.0.1:8787/status"

    monkeypatch.setattr(cluster, "has_dashboard", lambda: True)
    assert cluster.dashboard_text(WithLink()) == "Dask dashboard: http://127.0.0.1:8787/status"
    monkeypatch.setattr(cluster, "has_dashboard", lambda: False)
    assert "off" in cluster.dashboard_text(WithLink()) and "pip install bokeh" in cluster.dashboard_text(client)


def test_without_the_batch_extra_the_command_says_what_to_install(monkeypatch: pytest.MonkeyPatch,
                                                                   capsys: pytest.CaptureFixture[str],
                                                                   tmp_path: Path) -> None:
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "pyarrow" else real(name, *a))
    assert batch_main(["x.ply", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert "pip install 'bsv[batch]'" in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_what_bsip_writes_the_inertial_parameters_of_a_cloud_item(inputs: dict[str, Any], tmp_path: Path) -> None:
    """``--what bsip`` on a cloud item, run directly (no cluster): bsip.json, bsip.csv and model.osim land in
    the item folder with the volumes, and the masses sum to the body-mass estimate."""
    import json

    from bsv.batch.task import run_item

    item = collect_items(inputs["inputs"][:1])[0]
    rec = run_item(item, str(tmp_path), Spec(what="bsip", params={"schedule": SCHEDULE}), "hash")
    assert rec["status"] == "ok", rec
    folder = tmp_path / item.name
    for name in ("fitted.ply", "volumes.json", "bsip.json", "bsip.csv", "model.osim"):
        assert (folder / name).is_file(), name
    doc = json.loads((folder / "bsip.json").read_text())
    masses = [seg["mass_kg"] for seg in doc["segments"].values()]
    assert len(masses) == 9 and sum(masses) == pytest.approx(doc["body_mass_kg"], rel=1e-9)

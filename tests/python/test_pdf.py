"""report.pdf laid out in a worker process (bsv.pdf) and a run's files written all or not at all
(bsv.staging): the worker gives the same PDF as this process, its errors arrive typed, a worker that dies
is replaced by this process, and a failure while the files are written leaves the output folder as it was.

A worker loads WeasyPrint for about a second; these tests start five of them (about 6 s)."""

from __future__ import annotations

import os
import stat
import sys
import time
from pathlib import Path

import pytest

from bsv import pdf
from bsv.errors import OutputExistsError, ReportError
from bsv.staging import STAGING_PREFIX, staged_outputs

DOC = ("<html><head><style>body{font-family:sans-serif}</style></head><body><h1>Report</h1>"
       "<table><tr><th>thigh</th><td>7.81 L</td></tr></table><p>" + "text " * 200 + "</p></body></html>")


def _fake_weasyprint(tmp_path: Path, body: str) -> Path:
    """A folder holding a ``weasyprint`` package whose import runs ``body``; put first on PYTHONPATH, the
    worker imports it instead of the real one (this process keeps the real one)."""
    pkg = tmp_path / "fake" / "weasyprint"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text(body)
    return pkg.parent


def test_the_worker_lays_out_the_same_pdf_as_this_process():
    with pdf.PdfRenderer(worker=True) as r:
        assert r.worker
        r.submit(DOC)
        from_worker = r.result()
    here = pdf.PdfRenderer(worker=False).start().render(DOC)
    assert from_worker[:5] == b"%PDF-" and from_worker.rstrip().endswith(b"%%EOF")
    assert here[:5] == b"%PDF-"
    assert abs(len(from_worker) - len(here)) < 0.05 * len(here)  # the same layout (dates and ids differ)


def test_the_workers_warm_up_is_shaped_like_the_report():
    from bsv import report

    doc = pdf._warm_up_document()
    assert doc == report.warm_up_document()
    assert report.CSS in doc and "data:image/png;base64," in doc and "data:image/jpeg;base64," in doc
    assert pdf.render_pdf(doc).startswith(b"%PDF-")


def test_libraries_are_looked_up_in_the_linkers_cache_only_while_weasyprint_loads():
    import ctypes.util

    if not sys.platform.startswith("linux"):
        pytest.skip("the linker's cache lookup (ldconfig) is Linux's")
    original = ctypes.util.find_library
    with pdf._libraries_from_ldconfig():
        assert ctypes.util.find_library is not original
        assert ctypes.util.find_library("pango-1.0") == original("pango-1.0")  # in the cache: the same answer
        assert ctypes.util.find_library("libpango-1.0-0") is None  # a name cffi tries first on Windows
    assert ctypes.util.find_library is original


def test_weasyprint_loads_with_the_usual_lookup_when_the_cache_lacks_a_library(tmp_path):
    # In a fresh interpreter whose linker's cache knows nothing, the import is retried with the usual
    # lookup (a library on LD_LIBRARY_PATH only, say) and succeeds.
    import subprocess

    code = ("import ctypes.util, sys\n"
            "ctypes.util._findSoname_ldconfig = lambda name: None\n"
            "from bsv import pdf\n"
            "pdf.require_pdf()\n"
            "assert 'weasyprint' in sys.modules\n"
            "print('ok')\n")
    env = dict(os.environ, PYTHONPATH=str(Path(pdf.__file__).resolve().parents[1]))
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path,
                         timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "ok"


def test_the_worker_leaves_the_cores_to_its_parent_until_the_report():
    if not hasattr(os, "getpriority"):
        pytest.skip("no process priorities here (os.getpriority)")
    own = os.getpriority(os.PRIO_PROCESS, 0)
    expected = min(19, own + pdf.WORKER_NICENESS)
    with pdf.PdfRenderer(worker=True) as r:
        assert r._proc is not None
        pid = r._proc.pid
        deadline = time.monotonic() + 60
        while os.getpriority(os.PRIO_PROCESS, pid) != expected and time.monotonic() < deadline:
            time.sleep(0.02)  # the worker lowers its priority once its interpreter is up
        assert os.getpriority(os.PRIO_PROCESS, pid) == expected
        assert r.render(DOC)[:5] == b"%PDF-"
    assert os.getpriority(os.PRIO_PROCESS, 0) == own  # this process keeps its own


def test_a_document_is_submitted_once():
    r = pdf.PdfRenderer(worker=False).start()
    with pytest.raises(RuntimeError, match="submit a document first"):
        r.result()
    r.submit(DOC)
    with pytest.raises(RuntimeError, match="one document per renderer"):
        r.submit(DOC)
    assert r.result()[:5] == b"%PDF-"


def test_a_worker_without_pango_says_what_to_install(tmp_path, monkeypatch):
    fake = _fake_weasyprint(tmp_path, "raise OSError(\"cannot load library 'libpango-1.0-0'\")\n")
    monkeypatch.setenv("PYTHONPATH", str(fake))
    r = pdf.PdfRenderer(worker=True).start()
    try:
        assert r.worker
        deadline = time.monotonic() + 60
        with pytest.raises(ReportError, match=r"apt-get install libpango-1\.0-0"):
            while time.monotonic() < deadline:  # check() does not wait: it raises once the worker has stopped
                r.check()
                time.sleep(0.05)
    finally:
        r.close()
    r2 = pdf.PdfRenderer(worker=True).start()  # and the same error from result(), which waits
    with pytest.raises(ReportError, match="pango"):
        r2.render(DOC)


def test_a_worker_that_dies_is_replaced_by_this_process(tmp_path, monkeypatch):
    fake = _fake_weasyprint(tmp_path, "import os\nos._exit(9)\n")  # killed, say, by the out-of-memory killer
    monkeypatch.setenv("PYTHONPATH", str(fake))
    with pdf.PdfRenderer(worker=True) as r:
        time.sleep(0.5)
        r.check()  # a worker that died of something else than a BSV error is not an error of the run
        assert r.render(DOC)[:5] == b"%PDF-"


def test_without_weasyprint_no_worker_starts_and_the_extra_is_named(monkeypatch):
    from bsv.errors import MissingExtraError

    monkeypatch.setitem(sys.modules, "weasyprint", None)  # import weasyprint -> ImportError
    with pytest.raises(MissingExtraError, match=r"body-segment-volumes\[frontend\]"):
        pdf.PdfRenderer(worker=True).start()


def test_a_worker_not_used_is_stopped():
    r = pdf.PdfRenderer(worker=True).start()
    proc = r._proc  # the worker process (private: no public handle on it)
    assert proc is not None and proc.poll() is None
    r.close()
    assert proc.poll() is not None


def test_a_run_that_fails_after_submitting_stops_the_worker_quietly():
    """An error between submit() and result() (a file that cannot be written) leaves the renderer to
    close(): no error of its own on top of the run's, and no worker left behind."""
    r = pdf.PdfRenderer(worker=True).start()
    proc = r._proc
    r.submit(DOC)
    r.close()
    assert proc is not None and proc.poll() is not None


def test_the_worker_only_where_it_pays(monkeypatch):
    import weasyprint  # loaded in this process: laying out here costs nothing more

    assert not pdf.worker_pays()
    assert not pdf.PdfRenderer().worker
    monkeypatch.delitem(sys.modules, "weasyprint")
    monkeypatch.setattr(pdf, "_started_before", False)
    monkeypatch.setattr(pdf, "_cores", lambda: 1)
    assert not pdf.worker_pays()
    monkeypatch.setattr(pdf, "_cores", lambda: 2)
    assert pdf.worker_pays()  # a fresh `bsv process`
    pdf.PdfRenderer(worker=False)  # not started: nothing changes
    assert pdf.worker_pays()
    monkeypatch.setitem(sys.modules, "weasyprint", weasyprint)
    pdf.PdfRenderer(worker=False).start()
    monkeypatch.delitem(sys.modules, "weasyprint")
    assert not pdf.worker_pays()  # the second report of a process: WeasyPrint is loaded here, once


# ----------------------------------------------------------------------------------------------------
# bsv.staging


def test_staged_files_arrive_together_with_the_usual_mode(tmp_path):
    out = tmp_path / "out"
    with staged_outputs(out, overwrite=False) as stage:
        (stage / "a.json").write_text("{}")
        (stage / "seg" / "front").mkdir(parents=True)
        (stage / "seg" / "front" / "m.png").write_bytes(b"png")
        os.chmod(stage / "a.json", 0o600)  # as a temporary file is created
        assert not (out / "a.json").exists()  # nothing in OUT before the end
    assert (out / "a.json").read_text() == "{}" and (out / "seg" / "front" / "m.png").read_bytes() == b"png"
    umask = os.umask(0o22)
    os.umask(umask)
    assert stat.S_IMODE((out / "a.json").stat().st_mode) == 0o666 & ~umask
    assert not [p for p in out.iterdir() if p.name.startswith(STAGING_PREFIX)]


def test_a_failed_run_leaves_the_folder_as_it_was(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "volumes.json").write_text("mine")
    with pytest.raises(ReportError), staged_outputs(out, overwrite=True) as stage:
        (stage / "volumes.json").write_text("new")
        (stage / "cloud.ply").write_text("new")
        raise ReportError("report.pdf could not be rendered by WeasyPrint: test")
    assert sorted(p.name for p in out.iterdir()) == ["volumes.json"]
    assert (out / "volumes.json").read_text() == "mine"


def test_a_file_that_appeared_meanwhile_is_not_overwritten(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(OutputExistsError, match=r"b\.txt"), staged_outputs(out, overwrite=False) as stage:
        (stage / "a.txt").write_text("new")
        (stage / "b.txt").write_text("new")
        (out / "b.txt").write_text("mine")
    assert sorted(p.name for p in out.iterdir()) == ["b.txt"] and (out / "b.txt").read_text() == "mine"
    with staged_outputs(out, overwrite=True) as stage:
        (stage / "b.txt").write_text("new")
    assert (out / "b.txt").read_text() == "new"


def test_a_move_that_fails_puts_every_file_back(tmp_path):
    """The last move fails (its target is a folder): the files already moved are taken out again and the
    ones they replaced put back, so OUT is as it was, and the error names the folder."""
    from bsv.errors import WriteError

    out = tmp_path / "out"
    out.mkdir()
    (out / "a.json").write_text("old a")
    (out / "z.png").mkdir()  # in the way of the last file
    with pytest.raises(WriteError, match="nothing was changed") as e, staged_outputs(out, overwrite=True) as stage:
        (stage / "a.json").write_text("new a")
        (stage / "b.ply").write_text("new b")
        (stage / "z.png").write_text("new z")
    assert e.value.path == str(out)
    assert sorted(p.name for p in out.iterdir()) == ["a.json", "z.png"]
    assert (out / "a.json").read_text() == "old a" and (out / "z.png").is_dir()

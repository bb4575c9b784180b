"""report.pdf: the report's HTML laid out by WeasyPrint, in this process or in a worker process that also
draws the report's figures.

WeasyPrint costs a fresh process about 0.4 s of one core to import (cffi loads pango and its companions,
their names looked up in the linker's cache: :func:`_import_renderer`) and 0.3-0.6 s to lay the report out;
matplotlib 0.3-0.5 s to import and 0.3 s to draw the figures. A fresh ``bsv process`` keeps one core busy
(GIL-bound imports, MediaPipe, the registration) and leaves the other mostly idle, so :class:`PdfRenderer`
starts ``python -m bsv.pdf`` (:func:`main`) first thing: it imports WeasyPrint and matplotlib while the
capture is segmented and registered, then reads the report on its standard input (a
:class:`bsv.report.ReportJob`: the documents with their figures still to draw), draws the figures, lays
report.pdf out and writes report.html's document and the PDF on its standard output (pickled: the two
processes are parent and child). The process that runs MediaPipe never imports matplotlib, and the worker
runs at a lower priority (:data:`WORKER_NICENESS`) so that its warm-up takes only what the parent leaves.

A process's later reports (a station, a batch worker, a notebook: WeasyPrint is loaded once and kept),
a process that has loaded WeasyPrint already or a machine with one core render in this process: :func:`render_pdf`, the function the worker
runs. A worker that cannot start or dies is replaced by this process: the report is never lost to it.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import os
import pickle
import queue
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import TracebackType
from typing import IO, TYPE_CHECKING, Any, NoReturn, Self

from .errors import BsvError, ReportError
from .extras import require

if TYPE_CHECKING:
    from .report import FigureJob, ReportJob

#: The module that renders the PDF (its extra: ``frontend``).
RENDERER_MODULE = "weasyprint"
#: A small document the worker lays out while it waits (text, a table, the report's font stack): the first
#: layout of a process pays for fontconfig, pango's font map and the user-agent style sheet.
WARM_UP_DOC = ('<html><head><style>body{font-family:system-ui,sans-serif}</style></head><body><h1>BSV</h1>'
               '<table><tr><th>segment</th><td>1.0</td></tr></table><p>warm-up</p></body></html>')
#: The worker's exit code when it fails with a BSV error (its message on stderr).
WORKER_ERROR_EXIT = 3


@contextlib.contextmanager
def _libraries_from_ldconfig() -> Iterator[None]:
    """While the block runs, ``ctypes.util.find_library`` answers from the dynamic linker's cache alone
    (``ldconfig -p``, each name once). WeasyPrint's import tries up to six names for each of its seven C
    libraries through cffi, which asks ``find_library`` about every name it cannot open directly; for a
    name the cache lacks, ``find_library`` then runs ``gcc`` and ``ld`` too: 0.1-0.15 s of a core in child
    processes and 0.15 s of waiting, while MediaPipe loads on the same two cores. Elsewhere than on Linux
    (no ldconfig lookup in ``ctypes.util``) nothing changes."""
    import ctypes.util

    from_cache = getattr(ctypes.util, "_findSoname_ldconfig", None)
    if from_cache is None or not sys.platform.startswith("linux"):
        yield
        return
    original = ctypes.util.find_library
    ctypes.util.find_library = functools.lru_cache(maxsize=None)(from_cache)
    try:
        yield
    finally:
        ctypes.util.find_library = original


def _import_renderer() -> None:
    """Imports WeasyPrint (:data:`RENDERER_MODULE`), its C libraries looked up in the linker's cache first
    (:func:`_libraries_from_ldconfig`); if that fails to find them (a library only on ``LD_LIBRARY_PATH``,
    say), the import is tried again with the usual lookup, whose error is the one raised."""
    if sys.modules.get(RENDERER_MODULE) is not None:
        return
    try:
        with _libraries_from_ldconfig():
            require(RENDERER_MODULE)
        return
    except OSError:
        pass
    require(RENDERER_MODULE)


def require_pdf() -> None:
    """Checks that report.pdf can be made (``bsv process`` calls it before any work): without WeasyPrint a
    :class:`bsv.errors.MissingExtraError` naming the ``frontend`` extra; without Debian's pango (WeasyPrint
    fails to load it) a :class:`bsv.errors.ReportError` naming the packages to install."""
    try:
        _import_renderer()
    except OSError as exc:
        raise ReportError(f"report.pdf needs Debian's pango for WeasyPrint ({exc}); install it with "
                          "`apt-get install libpango-1.0-0 libpangoft2-1.0-0`") from exc


def render_pdf(doc: str) -> bytes:
    """The PDF of a report's HTML (WeasyPrint; the data: URIs need no base URL)."""
    require_pdf()
    import weasyprint

    try:
        pdf: bytes = weasyprint.HTML(string=doc).write_pdf()
    except Exception as exc:  # WeasyPrint raises many kinds; name the file
        raise ReportError(f"report.pdf could not be rendered by WeasyPrint: {exc}") from exc
    return pdf


def _installed(module: str) -> bool:
    """Whether ``module`` can be found without importing it (a worker is started only then)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):  # sys.modules holds None or a module without a spec
        return False


def _cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # not Linux
        return os.cpu_count() or 1


#: Whether this process has started a PDF renderer before (see :func:`worker_pays`).
_started_before = False


def worker_pays() -> bool:
    """Whether a worker process makes report.pdf sooner here: this process's first report (one that makes
    more, a batch worker, a station, a notebook, loads WeasyPrint once and keeps it: a worker for each
    report would load it again each time), WeasyPrint not loaded yet here, and a second core to load it
    on."""
    return not _started_before and RENDERER_MODULE not in sys.modules and _cores() > 1


def _worker_env() -> dict[str, str]:
    """The worker's environment: this one, with this bsv's folder at the end of PYTHONPATH when it is not a
    site-packages folder (a source checkout on the path; a site-packages folder first on PYTHONPATH would
    come before the standard library)."""
    import site

    env = dict(os.environ)
    root = str(Path(__file__).resolve().parent.parent)
    sites = {str(Path(p).resolve()) for p in [*site.getsitepackages(), site.getusersitepackages()]}
    if root not in sites:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (env.get("PYTHONPATH"), root) if p)
    return env


def _reap(proc: subprocess.Popen[bytes]) -> None:
    """Closes a stopped (or killed) worker's pipes and waits for it. Not ``communicate()``: that flushes
    stdin, which :meth:`PdfRenderer.submit` has closed already."""
    for pipe in (proc.stdin, proc.stdout):
        if pipe is not None:
            with contextlib.suppress(OSError, ValueError):
                pipe.close()
    proc.wait()


def _render(doc: str | ReportJob, drawn: Mapping[str, Any] | None = None) -> tuple[str | None, bytes]:
    """(report.html's document, the PDF) of a :class:`bsv.report.ReportJob`, its figures drawn in this
    process (those of ``drawn`` before: :meth:`PdfRenderer.prepare`); (None, the PDF) of an HTML document."""
    if isinstance(doc, str):
        return None, render_pdf(doc)
    docs = doc.documents(drawn)
    return docs.get("html"), render_pdf(docs["pdf"])


def _unpickled_output(data: bytes) -> tuple[str | None, bytes] | None:
    """The worker's output (:func:`main`): (report.html's document or None, a PDF), or None when ``data`` is
    not that (a worker that was killed mid-way)."""
    try:
        out = pickle.loads(data)
    except Exception:  # truncated or empty: the worker did not finish
        return None
    ok = (isinstance(out, tuple) and len(out) == 2 and (out[0] is None or isinstance(out[0], str))
          and isinstance(out[1], bytes) and out[1].startswith(b"%PDF-"))
    return out if ok else None


class PdfRenderer:
    """Renders report.pdf, loading WeasyPrint as early as possible (module doc).

    ``worker``: True a worker process, False this process, None (the default) a worker when
    :func:`worker_pays`. Use it as a context manager (or :meth:`start` and :meth:`close`): :meth:`start`
    names a missing ``frontend`` extra at once and starts loading WeasyPrint; :meth:`check` raises the
    worker's error (pango missing) once known, without waiting; :meth:`submit` hands it the report's HTML or
    a :class:`bsv.report.ReportJob` and :meth:`result` returns the PDF (:meth:`report`: with a job's
    report.html; one document per renderer)."""

    def __init__(self, worker: bool | None = None) -> None:
        self.worker = worker_pays() if worker is None else worker
        self._proc: subprocess.Popen[bytes] | None = None
        self._doc: str | ReportJob | None = None
        self._done: tuple[str | None, bytes] | None = None
        self._err: IO[bytes] | None = None

    def start(self) -> Self:
        """Names a missing WeasyPrint (:class:`bsv.errors.MissingExtraError`) and starts loading it: in the
        worker, or here (then a missing pango raises :class:`bsv.errors.ReportError` now)."""
        global _started_before
        _started_before = True
        if self.worker and _installed(RENDERER_MODULE):
            try:
                # a file, not a pipe: the worker never waits on it (closed by _stderr)
                self._err = tempfile.TemporaryFile()  # noqa: SIM115
                # -P: not the current folder on the worker's path (a stray weasyprint.py there)
                self._proc = subprocess.Popen([sys.executable, "-P", "-m", __name__], stdin=subprocess.PIPE,
                                              stdout=subprocess.PIPE, stderr=self._err, env=_worker_env())
                return self
            except OSError:  # no process to be had: load it here
                self._stderr()
        self.worker = False
        require_pdf()  # a missing WeasyPrint: its MissingExtraError naming the extra
        return self

    def check(self) -> None:
        """Raises the worker's error (:class:`bsv.errors.ReportError`: pango missing) if it has stopped
        already; returns at once otherwise (a worker that stopped otherwise is replaced by this process)."""
        proc = self._proc
        if proc is not None and proc.poll() is not None:
            self._proc = None
            _reap(proc)
            self._failed(proc.returncode, self._stderr())

    def submit(self, doc: str | ReportJob) -> None:
        """Starts laying out ``doc``: a report's HTML, or a :class:`bsv.report.ReportJob` (the report with its
        figures still to draw: the worker draws them, then lays report.pdf out). The worker reads it and works
        while this process goes on; :meth:`result` returns the PDF (:meth:`report`, a job's report.html too).
        Without a worker, :meth:`result` does the work here."""
        if self._doc is not None:
            raise RuntimeError("PdfRenderer.submit: one document per renderer, and one was submitted")
        self._doc = doc
        self._send(("report", doc))
        if self._proc is not None and self._proc.stdin is not None:
            with contextlib.suppress(OSError):
                self._proc.stdin.close()

    def prepare(self, figures: Mapping[str, FigureJob]) -> None:
        """Has the worker draw ``figures`` now, before the report that shows them is submitted (``bsv
        process``: the fitted mesh's figures, :func:`bsv.report.mesh_figures`, while it computes the
        intervals). They must be the submitted :class:`bsv.report.ReportJob`'s own for the same keys.
        Without a worker nothing is drawn ahead (:meth:`result` draws everything)."""
        if self._doc is not None:
            raise RuntimeError("PdfRenderer.prepare: the report was submitted already")
        self._send(("figures", dict(figures)))

    def _send(self, message: tuple[str, Any]) -> None:
        """Writes one message to the worker (its reader thread takes it at once: :func:`_inbox`); a worker
        that died is left to :meth:`result`, which says why or renders here."""
        if self._proc is not None and self._proc.stdin is not None:
            with contextlib.suppress(OSError, ValueError):
                self._proc.stdin.write(pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL))
                self._proc.stdin.flush()

    def result(self) -> bytes:
        """The PDF of the submitted document (:func:`render_pdf`), from the worker if one was started."""
        return self.report()[1]

    def report(self) -> tuple[str | None, bytes]:
        """(report.html's document with its figures, the PDF) of a submitted :class:`bsv.report.ReportJob`;
        (None, the PDF) of a submitted HTML document. From the worker if one was started; a worker that died
        is replaced by this process (the figures drawn here then)."""
        doc, proc = self._doc, self._proc
        if doc is None:
            raise RuntimeError("PdfRenderer.result: submit a document first")
        if self._done is not None:
            return self._done
        if proc is not None:
            data = proc.stdout.read() if proc.stdout is not None else b""  # an interruption: close() reaps it
            _reap(proc)
            self._proc = None
            done = _unpickled_output(data) if proc.returncode == 0 else None
            if done is not None:
                self._stderr()
                self._done = done
                return done
            self._failed(proc.returncode, self._stderr())
        self._done = _render(doc)  # no worker, or it was killed or wrote something else than its output
        return self._done

    def render(self, doc: str) -> bytes:
        """:meth:`submit` then :meth:`result`: the PDF of ``doc``."""
        self.submit(doc)
        return self.result()

    def _stderr(self) -> bytes:
        """What the worker printed on stderr (its file closed then)."""
        err, self._err = self._err, None
        if err is None:
            return b""
        with err:
            err.seek(0)
            return err.read()

    @staticmethod
    def _failed(code: int | None, err: bytes) -> None:
        """The worker stopped: its BSV error raised here as a :class:`bsv.errors.ReportError`; other ends
        (killed, out of memory) return, and this process renders instead."""
        if code == WORKER_ERROR_EXIT:
            raise ReportError(err.decode("utf-8", "replace").strip())

    def close(self) -> None:
        """Stops a worker that has not rendered (the run failed or was interrupted)."""
        proc, self._proc = self._proc, None
        if proc is not None:
            if proc.poll() is None:
                proc.kill()
            _reap(proc)
        self._stderr()

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def main() -> int:
    """The worker (``python -m bsv.pdf``): loads WeasyPrint, lays out a document shaped like the report
    (:func:`_warm_up_document`), loads what the figures need (:func:`_warm_up_figures`), then takes the
    parent's messages on stdin (:func:`_inbox`): figures to draw ahead (:meth:`PdfRenderer.prepare`), then
    the report (:meth:`PdfRenderer.submit`: its HTML, or a :class:`bsv.report.ReportJob` whose other figures
    it draws), and writes (report.html's document or None, the PDF) on stdout. A BSV error (pango missing, a
    failed layout) is printed on stderr with exit code :data:`WORKER_ERROR_EXIT`."""
    out = os.fdopen(os.dup(1), "wb")  # the PDF's channel; whatever else writes to stdout goes to stderr
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    _yield_to_parent()
    inbox = _inbox(sys.stdin.buffer)
    try:
        require_pdf()
        with contextlib.suppress(BsvError):  # only a warm-up: the report's own layout says what fails
            render_pdf(_warm_up_document())  # fonts, styles, image decoders: ready before the report
        _warm_up_figures()
        drawn: dict[str, Any] = {}
        while True:
            kind, payload = inbox.get()
            if kind == "figures":  # PdfRenderer.prepare
                from .report import draw_ahead

                drawn.update(draw_ahead(payload))
            elif kind == "report":  # PdfRenderer.submit
                done = _render(payload, drawn)
                break
            else:  # the parent closed the pipe without a report (it failed or was interrupted)
                return 0
    except BsvError as exc:
        sys.stderr.write(f"{exc}\n")
        return WORKER_ERROR_EXIT
    with out:
        out.write(pickle.dumps(done, protocol=pickle.HIGHEST_PROTOCOL))
    return 0


def _warm_up_document() -> str:
    """:func:`bsv.report.warm_up_document` (the report's style sheet and elements), or the plain
    :data:`WARM_UP_DOC` when the report module cannot be imported here."""
    try:
        from .report import warm_up_document

        return warm_up_document()
    except Exception:  # a warm-up: the plain document warms most of it
        return WARM_UP_DOC


def _inbox(stream: IO[bytes]) -> queue.Queue[tuple[str, Any]]:
    """The parent's messages (pickled ``(kind, payload)`` tuples, :meth:`PdfRenderer._send`) read from
    ``stream`` by a thread as they arrive, so that the parent never waits on a full pipe while the worker
    warms up; ``("end", None)`` once the stream ends or breaks."""
    box: queue.Queue[tuple[str, Any]] = queue.Queue()

    def read() -> None:
        while True:
            try:
                message = pickle.load(stream)  # from this process's parent
            except Exception:  # EOFError: the parent closed the pipe; anything else: a broken message
                box.put(("end", None))
                return
            box.put(message)

    threading.Thread(target=read, name="bsv-pdf-inbox", daemon=True).start()
    return box


#: How much the worker lowers its scheduling priority (``nice``): its warm-up is not needed before the
#: report, and on two cores it competed with the parent's MediaPipe graph, reading and segmentation.
WORKER_NICENESS = 10


def _yield_to_parent() -> None:
    """Lowers the worker's priority by :data:`WORKER_NICENESS`: its imports and warm-ups run in the time the
    parent leaves free (``bsv process`` waits on MediaPipe's and the registration's native code, one core
    at a time, much of the run), and the parent's work before the report comes first. Not raised again (an
    unprivileged process cannot): when the report arrives the parent waits for it, and the worker has a core
    to itself. Where the priority cannot be changed, nothing changes."""
    with contextlib.suppress(AttributeError, OSError):
        os.nice(WORKER_NICENESS)


def _warm_up_figures() -> None:
    """Loads what the report's figures need (:func:`bsv.report.prepare_figures`: matplotlib, fonts, the
    image encoders) while the worker waits; nothing when the report module cannot be imported here (the
    job then says why)."""
    with contextlib.suppress(Exception):
        from .report import prepare_figures

        prepare_figures()


def _exit_now(status: int) -> NoReturn:
    """Ends the worker at once, its output flushed and closed: the interpreter's teardown of WeasyPrint's
    objects (0.07-0.1 s) would only keep :meth:`PdfRenderer.result` waiting for the exit."""
    with contextlib.suppress(Exception):
        sys.stderr.flush()
    os._exit(status)


__all__ = ["RENDERER_MODULE", "WORKER_ERROR_EXIT", "WORKER_NICENESS", "PdfRenderer", "main", "render_pdf", "require_pdf", "worker_pays"]


if __name__ == "__main__":
    _exit_now(main())

"""A run's output files, written all or not at all.

:func:`staged_outputs` gives a hidden temporary folder inside the output folder; the run writes every file
into it under its final relative path. When the block ends without error, each file is moved to its place
(:func:`os.replace`: each file appears whole, never half-written) with the usual file mode, and the folder
is removed; when it raises, the folder is removed and the output folder's files are as they were (the
output folder itself may have been created). The files it replaces are moved aside first and put back if
a move fails (:func:`commit`). So ``bsv process`` can write its files while report.pdf is still being laid
out, and a failure of that last file still leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import OutputExistsError, WriteError

#: Prefix of the temporary folder (hidden; a run killed outright may leave one, which can be deleted).
STAGING_PREFIX = ".bsv-run-"
#: Prefix of the folder inside the stage that holds the files being replaced until the new ones are in.
REPLACED_PREFIX = ".replaced-"


def file_mode() -> int:
    """The mode a new file gets from the umask (temporary files are created 0600)."""
    umask = os.umask(0o22)
    os.umask(umask)
    return 0o666 & ~umask


def commit(stage: Path, out: Path, overwrite: bool) -> list[Path]:
    """Moves every file under ``stage`` to the same relative path under ``out``; returns the final paths.
    Without ``overwrite`` an existing file (created since the run checked) raises
    :class:`bsv.errors.OutputExistsError` before anything moves. The files replaced are first moved aside
    into the stage; a move that fails (or an interruption) puts every file back as it was and raises
    :class:`bsv.errors.WriteError` (or the interruption)."""
    files = sorted(p for p in stage.rglob("*") if p.is_file())
    targets = [out / p.relative_to(stage) for p in files]
    existing = [str(t.relative_to(out)) for t in targets if t.exists() or t.is_symlink()]
    if existing and not overwrite:
        raise OutputExistsError(f"{out} already holds {', '.join(existing)}; pass overwrite=True to replace them")
    mode = file_mode()
    aside = Path(tempfile.mkdtemp(prefix=REPLACED_PREFIX, dir=stage))
    replaced: list[tuple[Path, Path]] = []
    moved: list[Path] = []
    try:
        for k, (src, dst) in enumerate(zip(files, targets, strict=True)):
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.chmod(src, mode)
            if dst.is_file() or dst.is_symlink():
                old = aside / str(k)
                os.replace(dst, old)
                replaced.append((dst, old))
            os.replace(src, dst)
            moved.append(dst)
    except BaseException as exc:
        for dst in moved:
            with contextlib.suppress(OSError):
                dst.unlink()
        for dst, old in replaced:
            with contextlib.suppress(OSError):
                os.replace(old, dst)
        if isinstance(exc, OSError):
            err = WriteError(f"cannot move the run's files into {out} ({exc}); nothing was changed there: is the "
                             "folder writable, or a file open in another program?")
            err.path = str(out)
            raise err from exc
        raise
    return targets


@contextlib.contextmanager
def staged_outputs(out: Path, overwrite: bool) -> Iterator[Path]:
    """A temporary folder inside ``out`` (created if needed) to write a run's files into; committed to
    ``out`` (:func:`commit`) when the block ends without error, removed in every case."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=out))
    except OSError as exc:
        err = WriteError(f"cannot write into {out} ({exc}); choose a writable output folder")
        err.path = str(out)
        raise err from exc
    try:
        yield stage
        commit(stage, out, overwrite)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


__all__ = ["REPLACED_PREFIX", "STAGING_PREFIX", "commit", "file_mode", "staged_outputs"]

"""A run's output files, written all or not at all.

:func:`staged_outputs` gives a hidden temporary folder inside the output folder; the run writes every file
into it under its final relative path. When the block ends without error, each file is moved to its place
(:func:`os.replace`: each file appears whole, never half-written) with the usual file mode, and the folder
is removed; when it raises, the folder is removed and the output folder is as it was. So ``bsv process``
can write its files while report.pdf is still being laid out, and a failure of that last file still leaves
nothing behind.
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


def _file_mode() -> int:
    """The mode a new file gets from the umask (temporary files are created 0600)."""
    umask = os.umask(0o22)
    os.umask(umask)
    return 0o666 & ~umask


def commit(stage: Path, out: Path, overwrite: bool) -> list[Path]:
    """Moves every file under ``stage`` to the same relative path under ``out``; returns the final paths.
    Without ``overwrite`` an existing file (created since the run checked) raises
    :class:`bsv.errors.OutputExistsError` before anything moves."""
    files = sorted(p for p in stage.rglob("*") if p.is_file())
    targets = [out / p.relative_to(stage) for p in files]
    existing = [str(t.relative_to(out)) for t in targets if t.exists() or t.is_symlink()]
    if existing and not overwrite:
        raise OutputExistsError(f"{out} already holds {', '.join(existing)}; pass overwrite=True to replace them")
    mode = _file_mode()
    for src, dst in zip(files, targets, strict=True):
        try:
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.chmod(src, mode)
            os.replace(src, dst)
        except OSError as exc:
            err = WriteError(f"cannot move {src.name} into {dst.parent} ({exc}); is the folder writable?")
            err.path = str(dst)
            raise err from exc
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


__all__ = ["STAGING_PREFIX", "commit", "staged_outputs"]

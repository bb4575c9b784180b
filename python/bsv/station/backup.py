"""``bsv station backup``: one consistent archive of the station (database + captures + results).

The SQLite database is copied with SQLite's online backup API (consistent while the station runs); the
archive is written to a temporary name and renamed, and an existing archive is never replaced.
"""

from __future__ import annotations

import sqlite3
import tarfile
import tempfile
from pathlib import Path

from ..errors import OutputExistsError
from .db import DB_FILE
from .jobs import CAPTURES, RESULTS


def backup(data: Path, out: Path) -> Path:
    """Write ``out`` (.tar.gz) holding ``station.sqlite3``, ``captures/`` and ``results/`` of ``data``."""
    if out.exists():
        raise OutputExistsError(f"{out} exists; choose another backup file name")
    db = data / DB_FILE
    if not db.is_file():
        raise FileNotFoundError(f"{db} does not exist: is {data} a station data folder?")
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out.parent) as tmp:
        copy = Path(tmp) / DB_FILE
        src, dst = sqlite3.connect(db), sqlite3.connect(copy)
        try:
            src.backup(dst)
        finally:
            dst.close()
            src.close()
        part = Path(tmp) / "backup.tar.gz"
        with tarfile.open(part, "w:gz") as tar:
            tar.add(copy, arcname=DB_FILE)
            for sub in (CAPTURES, RESULTS):
                if (data / sub).is_dir():
                    tar.add(data / sub, arcname=sub)
        part.rename(out)
    return out


__all__ = ["backup"]

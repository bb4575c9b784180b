"""``bsv station backup``: one consistent archive of the station: every table as JSON (``tables.json``,
readable on any database), the embedded SQLite file itself when the station uses it, and the
``captures/`` and ``results/`` folders.

The SQLite file is copied with SQLite's online backup API (consistent while the station runs); the
archive is written under a temporary name and renamed, and an existing archive is never replaced.
"""

from __future__ import annotations

import json
import sqlite3
import tarfile
import tempfile
from pathlib import Path
from typing import Any

from sqlalchemy import select

from ..errors import OutputExistsError
from .db import DB_FILE, default_url, make_engine
from .jobs import CAPTURES, RESULTS
from .models import Base


def _json(v: Any) -> Any:
    return v.isoformat() if hasattr(v, "isoformat") else v


def tables_json(url: str) -> str:
    """Every table of the station database at ``url`` as JSON ({table: [row, ...]}), in one transaction."""
    engine = make_engine(url)
    try:
        with engine.begin() as conn:
            out = {t.name: [{k: _json(v) for k, v in row._mapping.items()} for row in conn.execute(select(t))]
                   for t in Base.metadata.sorted_tables}
    finally:
        engine.dispose()
    return json.dumps(out, indent=1)


def backup(data: Path, out: Path, url: str | None = None) -> Path:
    """Write ``out`` (.tar.gz): ``tables.json``, ``station.sqlite3`` (embedded database only),
    ``captures/`` and ``results/`` of ``data``. ``url``: the database (default: the embedded one)."""
    if out.exists():
        raise OutputExistsError(f"{out} exists; choose another backup file name")
    db = data / DB_FILE
    if url is None and not db.is_file():
        raise FileNotFoundError(f"{db} does not exist: is {data} a station data folder? (or give --db URL)")
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out.parent) as tmp:
        part = Path(tmp) / "backup.tar.gz"
        with tarfile.open(part, "w:gz") as tar:
            if url is None:
                copy = Path(tmp) / DB_FILE
                src, dst = sqlite3.connect(db), sqlite3.connect(copy)
                try:
                    src.backup(dst)
                finally:
                    dst.close()
                    src.close()
                tar.add(copy, arcname=DB_FILE)
                (Path(tmp) / "tables.json").write_text(tables_json(f"sqlite:///{copy}"))
            else:
                (Path(tmp) / "tables.json").write_text(tables_json(url))
            tar.add(Path(tmp) / "tables.json", arcname="tables.json")
            for sub in (CAPTURES, RESULTS):
                if (data / sub).is_dir():
                    tar.add(data / sub, arcname=sub)
        part.rename(out)
    return out


__all__ = ["backup", "default_url", "tables_json"]

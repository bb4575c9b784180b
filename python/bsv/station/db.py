"""Database engine and migrations: SQLite in WAL mode under the data folder by default, or any
SQLAlchemy URL (PostgreSQL: ``postgresql+psycopg://...``); the schema is brought up to date by the
Alembic migrations shipped inside the package."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event, text
from sqlalchemy.orm import sessionmaker

MIGRATIONS = Path(__file__).with_name("migrations")
#: File name of the embedded database inside the data folder.
DB_FILE = "station.sqlite3"


def default_url(data_dir: Path) -> str:
    """The embedded database: ``DATA/station.sqlite3``."""
    return f"sqlite:///{(data_dir / DB_FILE).resolve()}"


def _sqlite_pragmas(dbapi_conn: Any, _record: Any) -> None:
    cur = dbapi_conn.cursor()
    # WAL: readers never block the writer, and a kill -9 loses at most the transaction being written.
    cur.execute("PRAGMA journal_mode=WAL")
    # NORMAL in WAL mode: each commit is written to the WAL before it returns (a killed process loses
    # nothing committed), fsync only at checkpoints (a power cut may lose the last commits, never corrupts).
    cur.execute("PRAGMA synchronous=NORMAL")
    cur.execute("PRAGMA foreign_keys=ON")
    cur.execute("PRAGMA busy_timeout=30000")
    cur.close()


def make_engine(url: str) -> Engine:
    """An engine for ``url``; SQLite connections get WAL mode (synchronous NORMAL), foreign keys and a busy timeout."""
    if url.startswith("sqlite"):
        engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": 30})
        event.listen(engine, "connect", _sqlite_pragmas)
        return engine
    return create_engine(url, pool_pre_ping=True)


def migrate(engine: Engine) -> None:
    """Bring the schema to the newest Alembic revision (idempotent)."""
    from alembic import command
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    with engine.begin() as conn:
        cfg.attributes["connection"] = conn
        command.upgrade(cfg, "head")


def session_factory(engine: Engine) -> sessionmaker:
    """ORM sessions bound to ``engine`` (objects stay readable after commit)."""
    return sessionmaker(engine, expire_on_commit=False)


def integrity_check(engine: Engine) -> str:
    """SQLite's ``PRAGMA integrity_check`` ("ok" when the file is sound); "n/a" on other databases."""
    if engine.dialect.name != "sqlite":
        return "n/a"
    with engine.connect() as conn:
        return str(conn.execute(text("PRAGMA integrity_check")).scalar())


__all__ = ["DB_FILE", "MIGRATIONS", "default_url", "integrity_check", "make_engine", "migrate", "session_factory"]

"""``bsv station``: serve the station, or ``bsv station backup`` / ``bsv station adduser``."""

from __future__ import annotations

import argparse
import getpass
import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path


def _serve(argv: Sequence[str]) -> int:
    ap = argparse.ArgumentParser(prog="bsv station", description="The operator's web application.",
                                 epilog="Also: bsv station backup OUT.tar.gz [--data DIR]; "
                                        "bsv station adduser NAME --role operator|viewer [--data DIR]")
    ap.add_argument("--data", default=None, help="data folder (database, captures, reports); default ./bsv-station "
                                                 "(./bsv-station-demo with --demo)")
    ap.add_argument("--db", default=None, help="SQLAlchemy database URL (default: SQLite in DATA, WAL mode)")
    ap.add_argument("--host", default="127.0.0.1", help="address to listen on (default localhost; any other "
                                                        "address requires a login: see adduser)")
    ap.add_argument("--port", type=int, default=8000, help="port (default 8000)")
    ap.add_argument("--demo", action="store_true", help="a sample subject and a first virtual-rig session")
    a = ap.parse_args(list(argv))
    import uvicorn

    from .app import StationConfig, create_app

    data = Path(a.data or ("bsv-station-demo" if a.demo else "bsv-station"))
    config = StationConfig(data=data, db_url=a.db, host=a.host, port=a.port, demo=a.demo)
    app = create_app(config)
    if config.require_login:
        from sqlalchemy import func, select

        from .models import User

        with app.state.factory() as db:
            if not db.scalar(select(func.count(User.id))):
                print(f"bsv station: listening on {a.host} needs a login, and {data} has no user yet: run "
                      f"`bsv station adduser NAME --role operator --data {data}` first", file=sys.stderr)
                return 2
    print(f"BSV Station: http://{a.host}:{a.port}/  (data: {data.resolve()})", flush=True)
    uvicorn.run(app, host=a.host, port=a.port, log_level="info", workers=1)
    return 0


def _backup(argv: Sequence[str]) -> int:
    ap = argparse.ArgumentParser(prog="bsv station backup", description="Archive the station's data.")
    ap.add_argument("out", help="archive to write (.tar.gz; never replaced)")
    ap.add_argument("--data", default="bsv-station", help="data folder (default ./bsv-station)")
    ap.add_argument("--db", default=None, help="SQLAlchemy database URL (default: SQLite in DATA)")
    a = ap.parse_args(list(argv))
    from .backup import backup

    print(backup(Path(a.data), Path(a.out), a.db))
    return 0


def _adduser(argv: Sequence[str]) -> int:
    ap = argparse.ArgumentParser(prog="bsv station adduser", description="Add a login (password asked, or "
                                                                         "read from BSV_STATION_PASSWORD).")
    ap.add_argument("name")
    ap.add_argument("--role", choices=("operator", "viewer"), required=True)
    ap.add_argument("--data", default="bsv-station", help="data folder (default ./bsv-station)")
    ap.add_argument("--db", default=None, help="SQLAlchemy database URL (default: SQLite in DATA)")
    a = ap.parse_args(list(argv))
    from .db import default_url, make_engine, migrate, session_factory
    from .security import add_user

    password = os.environ.get("BSV_STATION_PASSWORD") or getpass.getpass(f"password for {a.name}: ")
    data = Path(a.data)
    data.mkdir(parents=True, exist_ok=True)
    engine = make_engine(a.db or default_url(data))
    migrate(engine)
    with session_factory(engine)() as db:
        try:
            add_user(db, a.name, password, a.role)
        except ValueError as e:
            print(f"bsv station adduser: {e}", file=sys.stderr)
            return 2
    print(f"user {a.name} ({a.role}) added")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``bsv station``."""
    args = list(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.INFO)
    logging.getLogger("alembic").setLevel(logging.WARNING)
    if args and args[0] == "backup":
        return _backup(args[1:])
    if args and args[0] == "adduser":
        return _adduser(args[1:])
    return _serve(args)


__all__ = ["main"]

"""BSV Station: the operator's web application (subjects, sessions, captures, follow-up comparison).

``bsv station [--data DIR] [--db URL] [--host 127.0.0.1] [--port 8000] [--demo]`` serves it
(:mod:`bsv.station.cli`); :func:`create_app` builds the FastAPI application. Modules: ``models``
(tables), ``db`` (engine, WAL, Alembic migrations), ``jobs`` (queue and worker process), ``rig``
(capture sources), ``uncertainty`` (intervals and the comparison rule), ``charts``, ``security``
(login, CSRF, roles, audit), ``backup``.
"""

from __future__ import annotations

from .app import StationConfig, create_app

__all__ = ["StationConfig", "create_app"]

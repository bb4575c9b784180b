"""Alembic migrations of the station database (package data; run by :func:`bsv.station.db.migrate`)."""

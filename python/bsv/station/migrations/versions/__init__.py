"""Alembic revisions of the station database."""

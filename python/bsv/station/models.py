"""The station's database tables (SQLAlchemy 2 declarative models).

A *subject* (pseudonymous code, never a name) has *sessions* (one visit = one capture folder with the
calibration used); every processing of a session's capture is a *result* (volumes JSON with its
intervals, report folder, software version, operator). Nothing is updated in place: re-processing adds a
result linked to the same session. *Jobs* are the queue of captures and processings run by the worker
process; *users* and *audit events* serve the login and the audit log.
"""

from __future__ import annotations

import datetime as dt

from sqlalchemy import JSON, DateTime, Float, ForeignKey, Integer, String, Text
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship


def utcnow() -> dt.datetime:
    """The current time, UTC (naive datetimes are stored as UTC)."""
    return dt.datetime.now(dt.UTC).replace(tzinfo=None)


class Base(DeclarativeBase):
    """Declarative base of every station table."""


class Subject(Base):
    """A person measured at the station, known only by a pseudonymous code."""

    __tablename__ = "subjects"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    code: Mapped[str] = mapped_column(String(32), unique=True, index=True)
    sex: Mapped[str] = mapped_column(String(8))
    birth_year: Mapped[int | None] = mapped_column(Integer, nullable=True)
    height_m: Mapped[float | None] = mapped_column(Float, nullable=True)
    mass_kg: Mapped[float | None] = mapped_column(Float, nullable=True)
    notes: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    sessions: Mapped[list[Session]] = relationship(back_populates="subject", order_by="Session.created_at")


class Session(Base):
    """One visit: a capture folder (relative to the data folder), its source and the calibration used."""

    __tablename__ = "sessions"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    subject_id: Mapped[int] = mapped_column(ForeignKey("subjects.id"), index=True)
    capture_dir: Mapped[str] = mapped_column(String(255))
    calibration: Mapped[str] = mapped_column(String(255))
    source: Mapped[str] = mapped_column(String(16))
    source_info: Mapped[dict] = mapped_column(JSON, default=dict)
    operator: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    subject: Mapped[Subject] = relationship(back_populates="sessions")
    results: Mapped[list[Result]] = relationship(back_populates="session", order_by="Result.id")

    @property
    def latest(self) -> Result | None:
        """The newest result of this session (re-processings add results; none is overwritten)."""
        return self.results[-1] if self.results else None


class Result(Base):
    """One processing of a session's capture: the volumes JSON (with intervals when the pipeline gives
    them), the report folder (relative to the data folder), the software version and the operator."""

    __tablename__ = "results"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("sessions.id"), index=True)
    volumes: Mapped[dict] = mapped_column(JSON)
    report_dir: Mapped[str] = mapped_column(String(255))
    software_version: Mapped[str] = mapped_column(String(64))
    operator: Mapped[str] = mapped_column(String(64))
    parameters: Mapped[dict] = mapped_column(JSON, default=dict)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    session: Mapped[Session] = relationship(back_populates="results")


class Job(Base):
    """A capture (then processing) or a re-processing, run by the worker process.

    ``state``: queued -> capturing -> processing -> done | failed. ``message`` holds the pipeline's
    error message when it failed."""

    __tablename__ = "jobs"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    kind: Mapped[str] = mapped_column(String(16))
    state: Mapped[str] = mapped_column(String(16), index=True, default="queued")
    subject_id: Mapped[int] = mapped_column(ForeignKey("subjects.id"), index=True)
    session_id: Mapped[int | None] = mapped_column(ForeignKey("sessions.id"), nullable=True)
    result_id: Mapped[int | None] = mapped_column(ForeignKey("results.id"), nullable=True)
    params: Mapped[dict] = mapped_column(JSON, default=dict)
    operator: Mapped[str] = mapped_column(String(64))
    step: Mapped[str] = mapped_column(String(128), default="waiting in the queue")
    progress: Mapped[float] = mapped_column(Float, default=0.0)
    message: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    finished_at: Mapped[dt.datetime | None] = mapped_column(DateTime, nullable=True)


class User(Base):
    """A login of the station (needed when it listens on another address than localhost)."""

    __tablename__ = "users"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(64), unique=True)
    password_hash: Mapped[str] = mapped_column(String(255))
    role: Mapped[str] = mapped_column(String(16))
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)


class AuditEvent(Base):
    """Who did what when: captures, views, exports, logins. ``target`` is a table:id, never personal data."""

    __tablename__ = "audit"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow, index=True)
    user: Mapped[str] = mapped_column(String(64))
    action: Mapped[str] = mapped_column(String(32))
    target: Mapped[str] = mapped_column(String(64), default="")


__all__ = ["AuditEvent", "Base", "Job", "Result", "Session", "Subject", "User", "utcnow"]

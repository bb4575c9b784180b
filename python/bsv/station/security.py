"""Login, roles, CSRF and the audit log.

On localhost (the default) the station trusts the local operator (user "local", role operator). On any
other address every page needs a login: passwords are hashed with Argon2id (argon2-cffi, memory-hard),
the session lives in a signed cookie (Starlette's SessionMiddleware, SameSite=strict), and every form
carries a CSRF token checked on POST. Roles: ``operator`` (everything) and ``viewer`` (pages and exports,
no capture, no new subject). The audit log records captures, views, exports and logins with the user and
a ``table:id`` target only (no personal data).
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
from dataclasses import dataclass
from pathlib import Path

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError
from sqlalchemy import select
from sqlalchemy.orm import Session as DbSession

from .models import AuditEvent, User

ROLES = ("operator", "viewer")
_hasher = PasswordHasher()


def is_loopback(host: str) -> bool:
    """True for 127.0.0.0/8, ::1 and "localhost" (the only addresses served without login)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def hash_password(password: str) -> str:
    """Argon2id hash of ``password``."""
    return _hasher.hash(password)


def verify_password(stored: str, password: str) -> bool:
    """True when ``password`` matches the stored Argon2 hash."""
    try:
        return _hasher.verify(stored, password)
    except (VerificationError, InvalidHashError):
        return False


@dataclass(frozen=True)
class Principal:
    """The user a request acts for."""

    name: str
    role: str

    @property
    def can_operate(self) -> bool:
        """Operators create subjects and run captures; viewers only look and export."""
        return self.role == "operator"


#: The local operator, when the station listens on localhost only.
LOCAL = Principal("local", "operator")


def add_user(db: DbSession, name: str, password: str, role: str) -> User:
    """Create a login; ``ValueError`` with the reason when the name, password or role is not acceptable."""
    if role not in ROLES:
        raise ValueError(f"role must be one of {ROLES}, got {role!r}")
    if not name or len(name) > 64 or not name.replace("_", "").replace("-", "").replace(".", "").isalnum():
        raise ValueError("user name: 1-64 letters, digits, '_', '-', '.'")
    if len(password) < 10:
        raise ValueError("password: at least 10 characters")
    if db.scalars(select(User).where(User.name == name)).first() is not None:
        raise ValueError(f"user {name!r} exists already")
    user = User(name=name, password_hash=hash_password(password), role=role)
    db.add(user)
    db.commit()
    return user


def authenticate(db: DbSession, name: str, password: str) -> Principal | None:
    """The principal for a correct name and password, else None (same time either way: Argon2 runs)."""
    user = db.scalars(select(User).where(User.name == name)).first()
    if user is None:
        verify_password(_DUMMY, password)
        return None
    return Principal(user.name, user.role) if verify_password(user.password_hash, password) else None


_DUMMY = _hasher.hash("not a password of anyone")


def csrf_token(session: dict) -> str:
    """The session's CSRF token (created on first use)."""
    tok = session.get("csrf")
    if not isinstance(tok, str):
        tok = secrets.token_urlsafe(32)
        session["csrf"] = tok
    return tok


def csrf_ok(session: dict, given: str | None) -> bool:
    """True when the form's token equals the session's (constant-time)."""
    tok = session.get("csrf")
    return isinstance(tok, str) and isinstance(given, str) and hmac.compare_digest(tok, given)


def secret_key(data: Path) -> str:
    """The cookie-signing key in ``data/secret.key`` (created once, mode 0600)."""
    path = data / "secret.key"
    if not path.exists():
        tmp = path.with_suffix(".tmp")
        tmp.write_text(secrets.token_urlsafe(48))
        tmp.chmod(0o600)
        tmp.rename(path)
    return path.read_text().strip()


def audit(db: DbSession, who: Principal, action: str, target: str = "") -> None:
    """Append an audit event (committed with the caller's transaction)."""
    db.add(AuditEvent(user=who.name, action=action, target=target))


__all__ = ["LOCAL", "ROLES", "Principal", "add_user", "audit", "authenticate", "csrf_ok", "csrf_token", "hash_password",
           "is_loopback", "secret_key", "verify_password"]

"""Console users, their roles and their login sessions.

Passwords are hashed with Argon2id (argon2-cffi); session tokens are random and only
their SHA-256 is stored, so a copy of the database gives no way in.
"""

from __future__ import annotations

import hashlib
import secrets
import time
from enum import StrEnum
from functools import cache

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError
from sqlalchemy import Boolean, Float, ForeignKey, Integer, String, select
from sqlalchemy.orm import Mapped, Session, mapped_column

from proxima.settings import check_password_strength
from proxima.store.base import Base

_hasher = PasswordHasher()


class Role(StrEnum):
    SUPERVISOR = "supervisor"  # start runs, label, promote models, stop drones
    VIEWER = "viewer"  # read only


class User(Base):
    __tablename__ = "users"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    username: Mapped[str] = mapped_column(String(64), unique=True, nullable=False)
    password_hash: Mapped[str] = mapped_column(String(256), nullable=False)
    role: Mapped[str] = mapped_column(String(16), nullable=False)
    must_change_password: Mapped[bool] = mapped_column(Boolean, nullable=False, default=False)
    disabled: Mapped[bool] = mapped_column(Boolean, nullable=False, default=False)
    created_at: Mapped[float] = mapped_column(Float, nullable=False, default=time.time)


class UserSession(Base):
    __tablename__ = "user_sessions"

    token_sha256: Mapped[str] = mapped_column(String(64), primary_key=True)
    user_id: Mapped[int] = mapped_column(
        ForeignKey("users.id", ondelete="CASCADE"), nullable=False, index=True
    )
    created_at: Mapped[float] = mapped_column(Float, nullable=False)
    expires_at: Mapped[float] = mapped_column(Float, nullable=False)


def hash_password(password: str) -> str:
    """An Argon2id hash of `password` (salted, parameters inside the string)."""
    return _hasher.hash(password)


def verify_password(password_hash: str, password: str) -> bool:
    """Whether `password` matches `password_hash`; never raises on a mismatch."""
    try:
        return _hasher.verify(password_hash, password)
    except (VerificationError, InvalidHashError):
        return False


def _token_digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


def create_user(
    db: Session,
    username: str,
    password: str,
    role: Role | str,
    *,
    must_change_password: bool = False,
    check_strength: bool = True,
) -> User:
    """Add a user (committed).

    Raises:
        ValueError: unknown role, weak password, or the name is taken.
    """
    role = Role(role)
    if check_strength:
        check_password_strength(password)
    if db.scalar(select(User).where(User.username == username)) is not None:
        raise ValueError(f"user {username!r} already exists")
    user = User(
        username=username,
        password_hash=hash_password(password),
        role=str(role),
        must_change_password=must_change_password,
        created_at=time.time(),
    )
    db.add(user)
    db.commit()
    return user


def authenticate(db: Session, username: str, password: str) -> User | None:
    """The user if the name and password match and the account is enabled."""
    user = db.scalar(select(User).where(User.username == username))
    if user is None:
        # Hash anyway so that a missing name takes as long as a wrong password.
        verify_password(_dummy_hash(), password)
        return None
    if user.disabled or not verify_password(user.password_hash, password):
        return None
    if _hasher.check_needs_rehash(user.password_hash):
        user.password_hash = hash_password(password)
        db.commit()
    return user


def set_password(db: Session, user: User, password: str) -> None:
    """Change a password (checked for strength) and clear the must-change flag.

    Raises:
        ValueError: weak password.
    """
    check_password_strength(password)
    user.password_hash = hash_password(password)
    user.must_change_password = False
    db.commit()


def open_session(db: Session, user: User, ttl_s: float) -> tuple[str, float]:
    """A new random session token for `user` and its expiry (unix time)."""
    token = secrets.token_urlsafe(32)
    now = time.time()
    db.add(
        UserSession(
            token_sha256=_token_digest(token),
            user_id=user.id,
            created_at=now,
            expires_at=now + ttl_s,
        )
    )
    db.commit()
    return token, now + ttl_s


def user_for_token(db: Session, token: str) -> User | None:
    """The enabled user a live session token belongs to, else None."""
    row = db.get(UserSession, _token_digest(token))
    if row is None or row.expires_at < time.time():
        return None
    user = db.get(User, row.user_id)
    if user is None or user.disabled:
        return None
    return user


def close_session(db: Session, token: str) -> None:
    """Forget a session token (log out)."""
    row = db.get(UserSession, _token_digest(token))
    if row is not None:
        db.delete(row)
        db.commit()


def close_other_sessions(db: Session, user: User, keep_token: str) -> int:
    """Forget every session of `user` but the one of `keep_token` (after a password
    change, a stolen token stops working); returns how many were closed."""
    keep = _token_digest(keep_token)
    rows = db.scalars(
        select(UserSession).where(UserSession.user_id == user.id, UserSession.token_sha256 != keep)
    ).all()
    for row in rows:
        db.delete(row)
    db.commit()
    return len(rows)


def count_users(db: Session) -> int:
    return len(db.scalars(select(User.id)).all())


def ensure_first_supervisor(
    db: Session, username: str | None, password: str | None
) -> tuple[str, str] | None:
    """Create the first supervisor when there are no users yet.

    With `username` and `password` (from PROXIMA_ADMIN_USER / PROXIMA_ADMIN_PASSWORD) that
    account is created. Without them an `admin` account gets a random one-time password
    that must be changed at first login; it is returned once (to be printed) and never
    stored in clear. Returns None when users already existed or the credentials came from
    the environment.
    """
    if count_users(db) > 0:
        return None
    if username and password:
        create_user(db, username, password, Role.SUPERVISOR)
        return None
    one_time = secrets.token_urlsafe(12)
    create_user(
        db, "admin", one_time, Role.SUPERVISOR, must_change_password=True, check_strength=False
    )
    return "admin", one_time


@cache
def _dummy_hash() -> str:
    return _hasher.hash(secrets.token_urlsafe(16))

"""Dependency aliases for the routers: the console's services, a database session and
the logged-in user (any role, or a supervisor)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated

from fastapi import Depends, HTTPException, Request, status
from sqlalchemy.orm import Session
from starlette.requests import HTTPConnection

from proxima.api.auth import AuthUser, token_from
from proxima.api.services import Console
from proxima.store.users import user_for_token


def get_console(conn: HTTPConnection) -> Console:
    return conn.app.state.console


ConsoleDep = Annotated[Console, Depends(get_console)]


def get_db(console: ConsoleDep) -> Iterator[Session]:
    with console.sessions() as db:
        yield db


DbDep = Annotated[Session, Depends(get_db)]


def _user(request: Request, console: Console) -> AuthUser:
    token = token_from(request)
    if token is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "not logged in: POST /api/auth/login, then send Authorization: Bearer TOKEN",
            headers={"WWW-Authenticate": "Bearer"},
        )
    with console.sessions() as db:
        user = user_for_token(db, token)
        if user is None:
            raise HTTPException(
                status.HTTP_401_UNAUTHORIZED,
                "session expired or unknown; log in again",
                headers={"WWW-Authenticate": "Bearer"},
            )
        return AuthUser.of(user, token)


def user_allowing_password_change(request: Request, console: ConsoleDep) -> AuthUser:
    """Any logged-in user, even one that must still change a one-time password."""
    return _user(request, console)


def current_user(request: Request, console: ConsoleDep) -> AuthUser:
    """A logged-in user with a password of their own."""
    user = _user(request, console)
    if user.must_change_password:
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            "change the one-time password first: POST /api/auth/password",
        )
    return user


def require_supervisor(user: Annotated[AuthUser, Depends(current_user)]) -> AuthUser:
    if not user.is_supervisor:
        raise HTTPException(
            status.HTTP_403_FORBIDDEN, f"user {user.username!r} is a viewer: read only"
        )
    return user


PendingUser = Annotated[AuthUser, Depends(user_allowing_password_change)]
CurrentUser = Annotated[AuthUser, Depends(current_user)]
SupervisorUser = Annotated[AuthUser, Depends(require_supervisor)]

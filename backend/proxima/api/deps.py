"""Dependency aliases for the routers: the console's services, a database session, the
logged-in user (any role, or a supervisor) and the audit log bound to the request.

HTTP routes take the session token from `Authorization: Bearer TOKEN` (FastAPI's
`HTTPBearer`, so the OpenAPI schema declares the scheme on every route that needs it);
`AUTH_ERRORS` says which error codes each user dependency can answer, and
`proxima.api.openapi` documents them on every route that uses it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Annotated, Any

from fastapi import Depends, HTTPException, Request, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy.orm import Session
from starlette.requests import HTTPConnection

from proxima.api.audit import RequestAudit
from proxima.api.auth import AuthUser
from proxima.api.services import Console
from proxima.store.users import user_for_token

bearer = HTTPBearer(
    auto_error=False,
    scheme_name="bearer",
    description="the token from POST /api/auth/login",
)
Credentials = Annotated[HTTPAuthorizationCredentials | None, Depends(bearer)]


def get_console(conn: HTTPConnection) -> Console:
    return conn.app.state.console


ConsoleDep = Annotated[Console, Depends(get_console)]


def get_db(console: ConsoleDep) -> Iterator[Session]:
    with console.sessions() as db:
        yield db


DbDep = Annotated[Session, Depends(get_db)]


def _user(credentials: HTTPAuthorizationCredentials | None, console: Console) -> AuthUser:
    if credentials is None or not credentials.credentials.strip():
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "not logged in: POST /api/auth/login, then send Authorization: Bearer TOKEN",
            headers={"WWW-Authenticate": "Bearer"},
        )
    token = credentials.credentials.strip()
    with console.sessions() as db:
        user = user_for_token(db, token)
        if user is None:
            raise HTTPException(
                status.HTTP_401_UNAUTHORIZED,
                "session expired or unknown; log in again",
                headers={"WWW-Authenticate": "Bearer"},
            )
        return AuthUser.of(user, token)


def user_allowing_password_change(credentials: Credentials, console: ConsoleDep) -> AuthUser:
    """Any logged-in user, even one that must still change a one-time password."""
    return _user(credentials, console)


def current_user(credentials: Credentials, console: ConsoleDep) -> AuthUser:
    """A logged-in user with a password of their own."""
    user = _user(credentials, console)
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


def get_audit(request: Request, console: ConsoleDep) -> RequestAudit:
    return RequestAudit(console.audit, request)


PendingUser = Annotated[AuthUser, Depends(user_allowing_password_change)]
CurrentUser = Annotated[AuthUser, Depends(current_user)]
SupervisorUser = Annotated[AuthUser, Depends(require_supervisor)]
AuditDep = Annotated[RequestAudit, Depends(get_audit)]

# The error codes each user dependency can answer (documented by proxima.api.openapi).
AUTH_ERRORS: dict[Callable[..., Any], tuple[int, ...]] = {
    user_allowing_password_change: (401,),
    current_user: (401, 403),
    require_supervisor: (401, 403),
}

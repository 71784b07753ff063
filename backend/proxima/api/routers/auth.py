"""Log in (throttled), log out, who am I, change my password; each recorded in the audit
log. Logging in also sets the 3D view's cookie (see `proxima.api.auth`)."""

from __future__ import annotations

import logging

from fastapi import APIRouter, HTTPException, Request, Response, status

from proxima.api.audit import client_address
from proxima.api.auth import clear_view_cookie, set_view_cookie
from proxima.api.deps import AuditDep, ConsoleDep, DbDep, PendingUser
from proxima.api.errors import errors
from proxima.api.schemas import LoginRequest, LoginResponse, PasswordChange, UserOut
from proxima.store.audit import AuditAction, AuditOutcome
from proxima.store.users import (
    User,
    authenticate,
    close_other_sessions,
    close_session,
    open_session,
    set_password,
    verify_password,
)

router = APIRouter(prefix="/auth", tags=["auth"])
log = logging.getLogger(__name__)


@router.post("/login", responses=errors(401, 429))
def login(
    body: LoginRequest,
    request: Request,
    response: Response,
    db: DbDep,
    console: ConsoleDep,
    audit: AuditDep,
) -> LoginResponse:
    """A session token for a user name and password. Failed logins slow down that user
    name and that client address: 429 with `Retry-After` while one is blocked."""
    address = client_address(request)
    refusal = console.throttle.check(body.username, address)
    if refusal is not None:
        by = "this address" if refusal.key == "address" else "this user name from this address"
        if refusal.first:  # once per block, so a flood writes one row, not thousands
            log.warning(
                "login throttled: user %r from %s blocked %d s (%s)",
                body.username, address, refusal.retry_after_s, refusal.key,
            )  # fmt: skip
            audit(
                AuditAction.LOGIN_THROTTLED,
                actor=body.username,
                target=body.username,
                outcome=AuditOutcome.REFUSED,
                retry_after_s=refusal.retry_after_s,
                blocked=refusal.key,
            )
        raise HTTPException(
            status.HTTP_429_TOO_MANY_REQUESTS,
            f"too many failed logins for {by}: try again in {refusal.retry_after_s} s",
            headers={"Retry-After": str(refusal.retry_after_s)},
        )
    user = authenticate(db, body.username, body.password)
    if user is None:
        blocked_s = console.throttle.failed(body.username, address)
        log.warning("failed login: user %r from %s", body.username, address)
        audit(
            AuditAction.LOGIN_FAILED,
            actor=body.username,
            target=body.username,
            outcome=AuditOutcome.REFUSED,
            blocked_s=round(blocked_s, 1),
        )
        raise HTTPException(status.HTTP_401_UNAUTHORIZED, "wrong user name or password")
    console.throttle.succeeded(body.username, address)
    token, expires = open_session(db, user, console.settings.server.session_ttl_s)
    audit(AuditAction.LOGIN, actor=user.username, target=user.username)
    set_view_cookie(response, token, console.settings.server)
    return LoginResponse(
        token=token,
        expires_at=expires,
        user=UserOut(
            username=user.username,
            role=user.role,
            must_change_password=user.must_change_password,
        ),
    )


@router.post("/logout")
def logout(
    user: PendingUser, response: Response, db: DbDep, console: ConsoleDep, audit: AuditDep
) -> dict[str, bool]:
    """End this session (its token and the 3D view's cookie stop working)."""
    close_session(db, user.token)
    clear_view_cookie(response, console.settings.server)
    audit(AuditAction.LOGOUT, actor=user.username, target=user.username)
    return {"ok": True}


@router.post("/view-cookie", status_code=status.HTTP_204_NO_CONTENT)
def view_cookie(user: PendingUser, response: Response, console: ConsoleDep) -> None:
    """Set the 3D view's cookie to this session's token (the 3D page calls it, so a
    browser whose cookie belongs to another tab's session sees the view too)."""
    set_view_cookie(response, user.token, console.settings.server)


@router.get("/me")
def me(user: PendingUser) -> UserOut:
    return UserOut(
        username=user.username, role=user.role, must_change_password=user.must_change_password
    )


@router.post("/password", responses=errors(403))
def change_password(body: PasswordChange, user: PendingUser, db: DbDep, audit: AuditDep) -> UserOut:
    """Change my password; every other session of mine ends (this one stays)."""
    row = db.get(User, user.id)
    if row is None:  # deleted between the session check and now
        raise HTTPException(status.HTTP_401_UNAUTHORIZED, "session expired or unknown")
    if not verify_password(row.password_hash, body.old_password):
        audit(
            AuditAction.PASSWORD,
            actor=user.username,
            target=user.username,
            outcome=AuditOutcome.REFUSED,
            reason="old password is wrong",
        )
        raise HTTPException(status.HTTP_403_FORBIDDEN, "old password is wrong")
    set_password(db, row, body.new_password)  # the schema has checked its strength
    closed = close_other_sessions(db, row, user.token)
    audit(AuditAction.PASSWORD, actor=user.username, target=user.username, sessions_closed=closed)
    return UserOut(username=row.username, role=row.role, must_change_password=False)

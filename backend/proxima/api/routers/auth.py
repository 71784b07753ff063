"""Log in, log out, who am I, change my password."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import ConsoleDep, DbDep, PendingUser
from proxima.api.schemas import LoginRequest, LoginResponse, PasswordChange, UserOut
from proxima.store.users import (
    User,
    authenticate,
    close_session,
    open_session,
    set_password,
    verify_password,
)

router = APIRouter(prefix="/auth", tags=["auth"])


@router.post("/login")
def login(body: LoginRequest, db: DbDep, console: ConsoleDep) -> LoginResponse:
    user = authenticate(db, body.username, body.password)
    if user is None:
        raise HTTPException(status.HTTP_401_UNAUTHORIZED, "wrong user name or password")
    token, expires = open_session(db, user, console.settings.server.session_ttl_s)
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
def logout(user: PendingUser, db: DbDep) -> dict[str, bool]:
    close_session(db, user.token)
    return {"ok": True}


@router.get("/me")
def me(user: PendingUser) -> UserOut:
    return UserOut(
        username=user.username, role=user.role, must_change_password=user.must_change_password
    )


@router.post("/password")
def change_password(body: PasswordChange, user: PendingUser, db: DbDep) -> UserOut:
    row = db.get(User, user.id)
    assert row is not None
    if not verify_password(row.password_hash, body.old_password):
        raise HTTPException(status.HTTP_403_FORBIDDEN, "old password is wrong")
    try:
        set_password(db, row, body.new_password)
    except ValueError as exc:
        raise HTTPException(status.HTTP_422_UNPROCESSABLE_CONTENT, str(exc)) from None
    return UserOut(username=row.username, role=row.role, must_change_password=False)

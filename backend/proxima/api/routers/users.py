"""User accounts (supervisors manage them, recorded in the audit log; everyone may list
them)."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, status
from sqlalchemy import select

from proxima.api.deps import AuditDep, CurrentUser, DbDep, SupervisorUser
from proxima.api.errors import errors
from proxima.api.schemas import UserCreate, UserOut
from proxima.store.audit import AuditAction, AuditOutcome
from proxima.store.users import User, create_user

router = APIRouter(prefix="/users", tags=["users"])


def _out(u: User) -> UserOut:
    return UserOut(
        username=u.username,
        role=u.role,
        must_change_password=u.must_change_password,
        disabled=u.disabled,
    )


@router.get("")
def list_users(_: CurrentUser, db: DbDep) -> list[UserOut]:
    return [_out(u) for u in db.scalars(select(User).order_by(User.id))]


@router.post("", status_code=status.HTTP_201_CREATED, responses=errors(409))
def add_user(body: UserCreate, me: SupervisorUser, db: DbDep, audit: AuditDep) -> UserOut:
    """Add a user; 409 when the name is taken."""
    if db.scalar(select(User).where(User.username == body.username)) is not None:
        audit(
            AuditAction.USER_CREATE,
            actor=me.username,
            target=body.username,
            outcome=AuditOutcome.REFUSED,
            reason="name taken",
        )
        raise HTTPException(status.HTTP_409_CONFLICT, f"user {body.username!r} already exists")
    try:
        user = create_user(db, body.username, body.password, body.role)
    except ValueError as exc:  # taken meanwhile (the schema has checked the rest)
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    audit(AuditAction.USER_CREATE, actor=me.username, target=user.username, role=user.role)
    return _out(user)


@router.post("/{username}/disable", responses=errors(404, 409))
def disable_user(username: str, me: SupervisorUser, db: DbDep, audit: AuditDep) -> UserOut:
    """Disable an account: its sessions stop working at once; 409 for your own."""
    user = db.scalar(select(User).where(User.username == username))
    if user is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no user {username!r}")
    if user.id == me.id:
        raise HTTPException(status.HTTP_409_CONFLICT, "you cannot disable yourself")
    user.disabled = True
    db.commit()
    audit(AuditAction.USER_DISABLE, actor=me.username, target=user.username)
    return _out(user)

"""User accounts (supervisors manage them; everyone may list them)."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException, status
from sqlalchemy import select

from proxima.api.deps import CurrentUser, DbDep, SupervisorUser
from proxima.api.schemas import UserCreate, UserOut
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


@router.post("", status_code=status.HTTP_201_CREATED)
def add_user(body: UserCreate, _: SupervisorUser, db: DbDep) -> UserOut:
    try:
        user = create_user(db, body.username, body.password, body.role)
    except ValueError as exc:
        raise HTTPException(status.HTTP_422_UNPROCESSABLE_CONTENT, str(exc)) from None
    return _out(user)


@router.post("/{username}/disable")
def disable_user(username: str, me: SupervisorUser, db: DbDep) -> UserOut:
    user = db.scalar(select(User).where(User.username == username))
    if user is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no user {username!r}")
    if user.id == me.id:
        raise HTTPException(status.HTTP_409_CONFLICT, "you cannot disable yourself")
    user.disabled = True
    db.commit()
    return _out(user)

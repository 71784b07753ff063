"""`GET /api/audit`: the audit log of supervisor actions and login events, for
supervisors, newest first, filtered and paged."""

from __future__ import annotations

from dataclasses import asdict
from typing import Annotated, Literal

from fastapi import APIRouter, Query

from proxima.api.deps import ConsoleDep, SupervisorUser
from proxima.api.schemas import AuditEntryOut, AuditPage
from proxima.store.audit import MAX_LIMIT

router = APIRouter(prefix="/audit", tags=["audit"])


@router.get("")
def audit_log(
    _: SupervisorUser,
    console: ConsoleDep,
    actor: Annotated[str | None, Query(max_length=64, description="a user name")] = None,
    action: Annotated[
        str | None,
        Query(
            max_length=64,
            pattern=r"^[a-z_]+(\.[a-z_]+)?$",
            description="an action (drone.stop) or an area: every action of it (drone)",
        ),
    ] = None,
    target: Annotated[str | None, Query(max_length=256)] = None,
    outcome: Literal["ok", "refused", "failed"] | None = None,
    since: Annotated[float | None, Query(ge=0, description="unix time, inclusive")] = None,
    until: Annotated[float | None, Query(ge=0, description="unix time, inclusive")] = None,
    before_id: Annotated[int | None, Query(ge=1, description="next_before_id of a page")] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_LIMIT)] = 100,
) -> AuditPage:
    rows = console.audit.store.query(
        actor=actor,
        action=action,
        target=target,
        outcome=outcome,
        since=since,
        until=until,
        before_id=before_id,
        limit=limit,
    )
    entries = [AuditEntryOut(**asdict(r)) for r in rows]
    more = len(rows) == limit and rows[-1].id > 1
    return AuditPage(entries=entries, next_before_id=rows[-1].id if more else None)

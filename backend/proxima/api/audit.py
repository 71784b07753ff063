"""The one service routers write the audit log through (`proxima.store.audit`).

Routers record an action after it has happened (or been refused), with who, what, the
outcome and the client address. A write that fails is logged and never raised: the
action is done by then, and an emergency stop must not fail for want of an audit row.
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import Request

from proxima.store.audit import AuditAction, AuditLog, AuditOutcome

log = logging.getLogger(__name__)


def client_address(request: Request) -> str:
    """The peer address of a request ("" when unknown). A reverse proxy in front of the
    console makes this the proxy's address: the console does not trust X-Forwarded-For."""
    return request.client.host if request.client else ""


class Audit:
    """Writes the audit log; shared by every request of one app."""

    def __init__(self, store: AuditLog) -> None:
        self.store = store

    def record(
        self,
        action: AuditAction | str,
        *,
        actor: str,
        target: str = "",
        outcome: AuditOutcome | str = AuditOutcome.OK,
        client: str = "",
        **detail: Any,
    ) -> None:
        try:
            self.store.record(
                actor=actor,
                action=action,
                target=target,
                outcome=outcome,
                client=client,
                detail=detail,
            )
        except Exception:
            log.exception("audit log: could not record %s by %s on %r", action, actor, target)


class RequestAudit:
    """`Audit` bound to one request, so a router names only the action."""

    def __init__(self, audit: Audit, request: Request) -> None:
        self.audit = audit
        self.client = client_address(request)

    def __call__(
        self,
        action: AuditAction | str,
        *,
        actor: str,
        target: str = "",
        outcome: AuditOutcome | str = AuditOutcome.OK,
        **detail: Any,
    ) -> None:
        self.audit.record(
            action, actor=actor, target=target, outcome=outcome, client=self.client, **detail
        )

"""Model checkpoints in models/ (with their model cards), and promoting one into the
live engine (an explicit supervisor action, recorded in the audit log)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import AuditDep, ConsoleDep, CurrentUser, SupervisorUser
from proxima.api.errors import errors
from proxima.api.services import Console
from proxima.store.audit import AuditAction, AuditOutcome

router = APIRouter(prefix="/models", tags=["models"])

CHECKPOINT_SUFFIXES = (".pt", ".pth")


def _card(path: Path) -> dict[str, Any] | None:
    for suffix in (".json", ".md"):
        for card in (path.with_suffix(suffix), path.with_name(path.stem + ".card" + suffix)):
            if card.is_file() and card != path:
                text = card.read_text(errors="replace")
                if suffix == ".json":
                    try:
                        return {"format": "json", "content": json.loads(text)}
                    except json.JSONDecodeError:
                        pass
                return {"format": "markdown", "content": text[:20000]}
    return None


def checkpoints(console: Console) -> list[Path]:
    root = console.settings.server.models_dir
    if not root.is_dir():
        return []
    return sorted(
        (p for p in root.rglob("*") if p.suffix in CHECKPOINT_SUFFIXES and p.is_file()),
        key=lambda p: p.stat().st_mtime,
        reverse=True,
    )


def _describe(console: Console, path: Path) -> dict[str, Any]:
    root = console.settings.server.models_dir
    active = console.promoter.active_checkpoint() if console.promoter else None
    return {
        "name": str(path.relative_to(root)),
        "size_bytes": path.stat().st_size,
        "modified": path.stat().st_mtime,
        "active": active is not None and Path(active).resolve() == path.resolve(),
        "card": _card(path),
    }


@router.get("")
def list_models(_: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    return {
        "models": [_describe(console, p) for p in checkpoints(console)],
        "promotion_available": console.promoter is not None,
    }


@router.post("/{name:path}/promote", responses=errors(404, 409, 503))
def promote(
    name: str, user: SupervisorUser, console: ConsoleDep, audit: AuditDep
) -> dict[str, Any]:
    """Load this checkpoint into the live engine; 409 when it is not a checkpoint the
    engine can run (labels, window size)."""
    root = console.settings.server.models_dir
    found = {str(p.relative_to(root)): p for p in checkpoints(console)}
    if name not in found:  # also refuses any path outside models/
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no checkpoint {name!r} in models/")
    if console.promoter is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE, "no live engine runs in this server to promote to"
        )
    previous = console.promoter.active_checkpoint()
    try:
        result = console.promoter.promote(str(found[name]))
    except ValueError as exc:
        audit(
            AuditAction.MODEL_PROMOTE,
            actor=user.username,
            target=name,
            outcome=AuditOutcome.REFUSED,
            reason=str(exc),
        )
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    audit(
        AuditAction.MODEL_PROMOTE,
        actor=user.username,
        target=name,
        previous=previous,
        pending=result.get("pending"),
    )
    return {"promoted": name, "by": user.username, **result}

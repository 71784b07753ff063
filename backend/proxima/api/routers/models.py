"""Model checkpoints in models/ (with their model cards and their figures on a held-out
set), and promoting one into the live engine: an explicit supervisor action, refused
when the candidate looks worse than the model in use unless overridden with a reason,
recorded in the audit log (whose rows are the promotion history a rollback follows)."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import AuditDep, ConsoleDep, CurrentUser, SupervisorUser
from proxima.api.errors import errors
from proxima.api.events import ModelEvent
from proxima.api.model_eval import concerns
from proxima.api.promote import promotion_history
from proxima.api.schemas import PromoteRequest
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


def _name(console: Console, path: str | Path | None) -> str:
    """A checkpoint's name in models/ (its path when it lies elsewhere, e.g. the shipped
    model)."""
    if not path:
        return ""
    root = console.settings.server.models_dir.resolve()
    p = Path(path).resolve()
    return str(p.relative_to(root)) if p.is_relative_to(root) else str(path)


def _describe(console: Console, path: Path) -> dict[str, Any]:
    root = console.settings.server.models_dir
    active = console.promoter.active_checkpoint() if console.promoter else None
    return {
        "name": str(path.relative_to(root)),
        "size_bytes": path.stat().st_size,
        "modified": path.stat().st_mtime,
        "active": active is not None and Path(active).resolve() == path.resolve(),
        "card": _card(path),
        "figures": console.evaluator.cached(path),  # None until evaluated
    }


def _found(console: Console, name: str) -> Path:
    root = console.settings.server.models_dir
    found = {str(p.relative_to(root)): p for p in checkpoints(console)}
    if name not in found:  # also refuses any path outside models/
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no checkpoint {name!r} in models/")
    return found[name]


def _figures(console: Console, path: str | Path | None) -> dict[str, Any] | None:
    """The held-out figures of `path`; None for no path (409 when it is no checkpoint)."""
    if not path:
        return None
    try:
        return console.evaluator.figures(path)
    except (FileNotFoundError, ValueError) as exc:
        raise HTTPException(status.HTTP_409_CONFLICT, f"{_name(console, path)}: {exc}") from None


def _comparison(console: Console, path: Path) -> dict[str, Any]:
    active = console.promoter.active_checkpoint() if console.promoter else None
    candidate = _figures(console, path)
    assert candidate is not None
    current = _figures(console, active)
    server = console.settings.server
    return {
        "candidate": {"name": _name(console, path), "figures": candidate},
        "active": {"name": _name(console, active), "figures": current} if active else None,
        "set": candidate["set"],
        "set_description": candidate["set_description"],
        "concerns": concerns(
            candidate, current, server.promotion_min_accuracy, server.promotion_tolerance
        ),
        "min_accuracy": server.promotion_min_accuracy,
        "tolerance": server.promotion_tolerance,
    }


@router.get("")
def list_models(_: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    return {
        "models": [_describe(console, p) for p in checkpoints(console)],
        "promotion_available": console.promoter is not None,
    }


@router.get("/active", responses=errors(503))
def active_model(_: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    """The model the live engine runs: its name, file date, its figures on the held-out
    set when evaluated, and the change that put it there (None: the configured one)."""
    if console.promoter is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE, "no live engine runs in this server"
        )
    path = console.promoter.active_checkpoint()
    history = promotion_history(console.audit.store, limit=2)
    name = _name(console, path)
    last = history[0] if history and history[0]["checkpoint"] == name else None
    modified = Path(path).stat().st_mtime if path and Path(path).is_file() else None
    return {
        "name": name,
        "modified": modified,
        "figures": console.evaluator.cached(path) if path else None,
        "since": last["ts"] if last else None,
        "by": last["by"] if last else "",
        "action": last["action"] if last else "configured",
        "rollback_to": last["previous"] if last else "",
        # Streams that run a model of their own (promoted for them: a calibration).
        "streams": {
            stream: _name(console, p)
            for stream, p in getattr(console.promoter, "stream_checkpoints", dict)().items()
        },
    }


@router.get("/history")
def history(_: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    """Every change of the live model, newest first (from the audit log)."""
    return {"history": promotion_history(console.audit.store)}


@router.get("/{name:path}/evaluation", responses=errors(404, 409))
def evaluation(name: str, _: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    """The checkpoint's figures beside the model in use's, on the held-out set, and the
    concerns that would make its promotion need an override."""
    return _comparison(console, _found(console, name))


def _swap(
    console: Console,
    audit: AuditDep,
    user: str,
    action: AuditAction,
    path: Path,
    name: str,
    comparison: dict[str, Any],
    override_reason: str = "",
) -> dict[str, Any]:
    assert console.promoter is not None
    previous = console.promoter.active_checkpoint()
    try:
        result = console.promoter.promote(str(path))
    except ValueError as exc:
        audit(action, actor=user, target=name, outcome=AuditOutcome.REFUSED, reason=str(exc))
        raise HTTPException(status.HTTP_409_CONFLICT, str(exc)) from None
    active = comparison["active"] or {}
    audit(
        action,
        actor=user,
        target=name,
        previous=previous,
        previous_name=_name(console, previous),
        path=str(path),
        figures=comparison["candidate"]["figures"],
        previous_figures=active.get("figures"),
        concerns=comparison["concerns"],
        override_reason=override_reason,
        pending=result.get("pending"),
    )
    console.bus.publish(
        ModelEvent(
            t=time.time(),
            checkpoint=name,
            previous=_name(console, previous),
            action=action.value.split(".", 1)[1],
            by=user,
        )
    )
    return {"promoted": name, "by": user, "previous": _name(console, previous), **result}


@router.post("/rollback", responses=errors(409, 503))
def rollback(user: SupervisorUser, console: ConsoleDep, audit: AuditDep) -> dict[str, Any]:
    """Put the model the newest change replaced back into the live engine (no guard: it
    ran before); 409 when there is no earlier model or it is gone."""
    if console.promoter is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE, "no live engine runs in this server"
        )
    changes = promotion_history(console.audit.store, limit=1)
    if not changes or not changes[0]["previous"]:
        raise HTTPException(status.HTTP_409_CONFLICT, "no earlier model to roll back to")
    target = changes[0]["previous"]
    path = Path(target)
    if not path.is_absolute():
        path = console.settings.server.models_dir / target
    if not path.is_file():
        raise HTTPException(status.HTTP_409_CONFLICT, f"{target}: the earlier model is gone")
    comparison = _comparison(console, path)
    return _swap(console, audit, user.username, AuditAction.MODEL_ROLLBACK, path, target,
                 comparison)  # fmt: skip


@router.post("/{name:path}/promote", responses=errors(404, 409, 503))
def promote(
    name: str,
    user: SupervisorUser,
    console: ConsoleDep,
    audit: AuditDep,
    body: PromoteRequest | None = None,
) -> dict[str, Any]:
    """Load this checkpoint into the live engine; 409 when it is not a checkpoint the
    engine can run (labels, window size), or when its held-out figures are below the
    minimum or the model in use's and no `override_reason` is given."""
    path = _found(console, name)
    if console.promoter is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE, "no live engine runs in this server to promote to"
        )
    try:
        comparison = _comparison(console, path)
    except HTTPException as exc:  # not a checkpoint the engine can run: a refusal too
        audit(AuditAction.MODEL_PROMOTE, actor=user.username, target=name,
              outcome=AuditOutcome.REFUSED, reason=str(exc.detail))  # fmt: skip
        raise
    reason = (body.override_reason or "").strip() if body else ""
    if comparison["concerns"] and not reason:
        audit(
            AuditAction.MODEL_PROMOTE,
            actor=user.username,
            target=name,
            outcome=AuditOutcome.REFUSED,
            reason="; ".join(comparison["concerns"]),
            figures=comparison["candidate"]["figures"],
        )
        raise HTTPException(
            status.HTTP_409_CONFLICT,
            f"{name} was not promoted: {'; '.join(comparison['concerns'])} (on the "
            f"{comparison['set']} set). Give an override reason to promote it anyway.",
        )
    return _swap(console, audit, user.username, AuditAction.MODEL_PROMOTE, path, name,
                 comparison, reason)  # fmt: skip

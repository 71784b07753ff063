"""Model checkpoints in models/ (with their model cards), and promoting one into the
live engine (an explicit supervisor action)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import ConsoleDep, CurrentUser, SupervisorUser
from proxima.api.services import Console

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


@router.post("/{name:path}/promote")
def promote(name: str, user: SupervisorUser, console: ConsoleDep) -> dict[str, Any]:
    """Load this checkpoint into the live engine."""
    root = console.settings.server.models_dir
    found = {str(p.relative_to(root)): p for p in checkpoints(console)}
    if name not in found:  # also refuses any path outside models/
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no checkpoint {name!r} in models/")
    if console.promoter is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE, "no live engine runs in this server to promote to"
        )
    try:
        result = console.promoter.promote(str(found[name]))
    except ValueError as exc:
        raise HTTPException(status.HTTP_422_UNPROCESSABLE_CONTENT, str(exc)) from None
    return {"promoted": name, "by": user.username, **result}

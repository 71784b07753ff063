"""`GET /api/health`: the one route open without a login (for probes and the demo)."""

from __future__ import annotations

from fastapi import APIRouter

from proxima import __version__

router = APIRouter(tags=["health"])


@router.get("/health")
def health() -> dict[str, str]:
    return {"status": "ok", "version": __version__}

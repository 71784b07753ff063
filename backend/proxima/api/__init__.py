"""The operator console's HTTP API: FastAPI app factory, one router per resource, and a
WebSocket hub that pushes bus events to browsers."""

from __future__ import annotations

from typing import Any

__all__ = ["create_app"]


def __getattr__(name: str) -> Any:
    # Lazy, so that `proxima --help` and `proxima sim-drone` do not import FastAPI.
    if name == "create_app":
        from proxima.api.app import create_app

        return create_app
    raise AttributeError(name)

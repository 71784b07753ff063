"""The operator console's HTTP API: FastAPI app factory, one router per resource, and a
WebSocket hub that pushes bus events to browsers."""

from proxima.api.app import create_app

__all__ = ["create_app"]

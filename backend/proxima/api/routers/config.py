"""What the browser needs to draw its pages: gesture names, where the 3D view is, the
user's role, the configured streams and drones."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from fastapi.openapi.utils import get_openapi

from proxima.api.deps import ConsoleDep, CurrentUser
from proxima.types import GESTURES

router = APIRouter(tags=["config"])


TRAINING_FORM = (
    "rounds",
    "local_epochs",
    "batch_size",
    "learning_rate",
    "fraction_fit",
    "min_clients",
    "strategy",
    "partition",
    "include_samples",
)


def _training_defaults(runner: Any) -> dict[str, Any]:
    """The runner's defaults for the fields of the Training page's form."""
    defaults = getattr(runner, "defaults", None)
    if defaults is None:
        return {}
    return {k: getattr(defaults, k) for k in TRAINING_FORM if hasattr(defaults, k)}


@router.get("/config")
def get_config(user: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    s = console.settings
    return {
        "user": {"username": user.username, "role": str(user.role)},
        "gestures": list(GESTURES),
        "viz_port": console.viz_port,
        "streams": [
            {"name": x.name, "drone": x.drone, "priority": x.priority, "kind": x.kind}
            for x in s.streams
        ],
        "drones": [d.name for d in s.drones],
        "training_available": console.training is not None,
        "training_defaults": _training_defaults(console.training),
        "estop_available": console.estop is not None,
    }


@router.get("/openapi.json", include_in_schema=False)
def openapi(request: Request, _: CurrentUser) -> dict[str, Any]:
    """The API's OpenAPI schema, for logged-in users only."""
    app = request.app
    return get_openapi(title=app.title, version=app.version, routes=app.routes)

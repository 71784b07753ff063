"""What the browser needs to draw its pages: gesture names, where the 3D view is, the
user's role, the configured streams and drones; and the OpenAPI schema."""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

from fastapi import APIRouter, Request

from proxima.api.auth import VIEW_PATH
from proxima.api.deps import ConsoleDep, CurrentUser
from proxima.api.interfaces import TrainingRunner
from proxima.api.openapi import openapi_schema
from proxima.api.schemas import TRAINING_FORM, CalibrationRequest, RecordingRequest
from proxima.federated.config import FLConfig
from proxima.types import GESTURES

router = APIRouter(tags=["config"])


def _training_form(runner: TrainingRunner | None) -> dict[str, dict[str, Any]]:
    """The Training page's form: each field's JSON schema (type, bounds, choices, from
    `FLConfig`) and the runner's default for it; `min_clients` at most the drones of the
    runner's federation (what the server checks too)."""
    defaults = runner.defaults if runner is not None else FLConfig()
    values = asdict(defaults)
    form = {
        name: {**FLConfig.field_schema(name), "default": values[name]} for name in TRAINING_FORM
    }
    if runner is not None:
        fleet = len(runner.clients)
        bound = form["min_clients"]
        bound["maximum"] = min(bound.get("maximum", fleet), fleet)
        bound["default"] = min(bound["default"], fleet)
    return form


def _form(schema: Any, names: tuple[str, ...]) -> dict[str, dict[str, Any]]:
    """Numeric fields with the bounds a request schema checks (one definition: the
    schema's own JSON schema)."""
    props = schema.model_json_schema()["properties"]
    keep = ("type", "minimum", "maximum", "default")
    return {name: {k: props[name][k] for k in keep if k in props[name]} for name in names}


def _recording_form() -> dict[str, dict[str, Any]]:
    """The Labelling page's numeric fields with the bounds `RecordingRequest` checks."""
    return _form(RecordingRequest, ("frames", "countdown_s"))


@router.get("/config")
def get_config(user: CurrentUser, console: ConsoleDep) -> dict[str, Any]:
    s = console.settings
    return {
        "user": {"username": user.username, "role": str(user.role)},
        "gestures": list(GESTURES),
        # The 3D view, through the console (one login covers both); None: not running.
        "view_url": f"{VIEW_PATH}/" if console.viz_port is not None else None,
        "streams": [
            {"name": x.name, "drone": x.drone, "priority": x.priority, "kind": x.kind}
            for x in s.streams
        ],
        "drones": [d.name for d in s.drones],
        "training_available": console.training is not None,
        "training_form": _training_form(console.training),
        "recording_form": _recording_form(),
        # The Calibration page's fields, with the bounds `CalibrationRequest` checks.
        "calibration_form": _form(CalibrationRequest, ("frames", "countdown_s", "epochs")),
        "estop_available": console.estop is not None,
    }


@router.get("/openapi.json", include_in_schema=False)
def openapi(request: Request, _: CurrentUser) -> dict[str, Any]:
    """The API's OpenAPI schema, for logged-in users only."""
    return openapi_schema(request.app)

"""The console's OpenAPI schema, made to tell the truth about errors.

FastAPI documents what a route declares; this adds what a route answers because of how
it is built: 401 and 403 from its user dependency (`deps.AUTH_ERRORS`), 400 where it
reads a body (FastAPI answers 400 to one it cannot decode), and 422 with `ErrorOut`
(instead of FastAPI's own validation body, which the app never sends) only where a
request can fail validation at all. Route-specific errors (404, 409, 429, 503)
are declared on the routes themselves with `errors.errors(...)`.
"""

from __future__ import annotations

import types
from typing import Any, Union, get_args, get_origin

from fastapi import FastAPI
from fastapi.dependencies.models import Dependant
from fastapi.dependencies.utils import get_flat_params
from fastapi.openapi.utils import get_openapi
from fastapi.routing import APIRoute

from proxima.api.deps import AUTH_ERRORS
from proxima.api.errors import DESCRIPTIONS, ErrorOut, http_routes

_REF = "#/components/schemas/"
_FASTAPI_422 = ("HTTPValidationError", "ValidationError")


def _calls(dependant: Dependant) -> set[Any]:
    out = set()
    for dep in dependant.dependencies:
        if dep.call is not None:
            out.add(dep.call)
        out |= _calls(dep)
    return out


def auth_errors(route: APIRoute) -> list[int]:
    """The error codes the route's user dependency can answer."""
    codes: set[int] = set()
    for call in _calls(route.dependant):
        codes.update(AUTH_ERRORS.get(call, ()))
    return sorted(codes)


def _is_plain_str(annotation: Any) -> bool:
    if annotation is str:
        return True
    if get_origin(annotation) in (Union, types.UnionType):
        return all(a in (str, type(None)) for a in get_args(annotation))
    return False


def can_fail_validation(route: APIRoute) -> bool:
    """Whether some request to the route can be refused with 422: it has a body, a
    required non-path parameter, or a parameter that is not a plain string."""
    if route.body_field is not None:
        return True
    for param in get_flat_params(route.dependant):
        info = param.field_info
        where = getattr(info, "in_", None)
        if getattr(where, "value", where) != "path" and param.field_info.is_required():
            return True
        if not _is_plain_str(info.annotation) or info.metadata:
            return True
    return False


def _error_response(code: int) -> dict[str, Any]:
    return {
        "description": DESCRIPTIONS[code],
        "content": {"application/json": {"schema": {"$ref": f"{_REF}ErrorOut"}}},
    }


def openapi_schema(app: FastAPI) -> dict[str, Any]:
    """The app's OpenAPI schema (built once, then cached on the app)."""
    if app.openapi_schema:
        return app.openapi_schema
    schema = get_openapi(
        title=app.title, version=app.version, description=app.description, routes=app.routes
    )
    for ctx in http_routes(app.routes):
        route = getattr(ctx, "original_route", ctx)
        if not isinstance(route, APIRoute) or not ctx.include_in_schema:
            continue
        codes = auth_errors(route) + ([400] if route.body_field is not None else [])
        validates = can_fail_validation(route)
        for method in ctx.methods:
            responses = schema["paths"][ctx.path_format][method.lower()]["responses"]
            default = responses.get("422", {}).get("content", {}).get("application/json", {})
            if default.get("schema", {}).get("$ref") == f"{_REF}HTTPValidationError":
                del responses["422"]
            if validates:
                responses.setdefault("422", _error_response(422))
            for code in codes:
                responses.setdefault(str(code), _error_response(code))
    components = schema.setdefault("components", {}).setdefault("schemas", {})
    for name in _FASTAPI_422:
        components.pop(name, None)
    error_schema = ErrorOut.model_json_schema(ref_template=f"{_REF}{{model}}")
    components.update(error_schema.pop("$defs", {}))
    components["ErrorOut"] = error_schema
    app.openapi_schema = schema
    return schema

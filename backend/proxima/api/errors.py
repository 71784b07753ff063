"""Error bodies of one shape, `ErrorOut`, for every error the API answers: an
`HTTPException` from a route, a request that does not match its schema (422, each problem
listed in `errors`), an unknown path (404) or method (405, with the `Allow` header listing
every method of that path).

Status codes mean one thing each: 400 a body that cannot be read at all; 401 no valid
session; 403 not allowed (a viewer, a one-time password not yet changed, a wrong old
password); 404 no such thing; 409 a well-formed request the server's state refuses (a
name taken, a run in progress, an unusable checkpoint, more minimum clients than drones,
a used confirmation id); 422 the request does not match its schema; 429 too many failed
logins (with `Retry-After`); 503 the subsystem behind the route does not run in this
server.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import BaseRoute, Match

DESCRIPTIONS: dict[int, str] = {
    400: "The body cannot be read as JSON text (e.g. it is not UTF-8)",
    401: "Not logged in, or the session expired",
    403: "Not allowed for this user",
    404: "No such resource",
    409: "Refused by the server's current state",
    422: "The request does not match its schema (each problem in `errors`)",
    429: "Too many failed logins: wait `Retry-After` seconds",
    503: "The subsystem behind this route does not run in this server",
}


class FieldError(BaseModel):
    """One problem of a request that does not match its schema."""

    loc: list[str | int] = Field(description='where: ["body", "rounds"], ["query", "limit"]')
    msg: str
    type: str


class ErrorOut(BaseModel):
    """Every error body: `detail` says what went wrong in words; `errors` lists each
    problem of a request that does not match its schema (empty otherwise)."""

    detail: str
    errors: list[FieldError] = Field(default_factory=list)


RETRY_AFTER = {
    "Retry-After": {
        "description": "seconds until a login may be tried again",
        "schema": {"type": "integer", "minimum": 1},
        "required": True,
    }
}


def errors(*codes: int) -> dict[int | str, dict[str, Any]]:
    """The `responses=` of a route that can answer these error codes, each with
    `ErrorOut` (and 429 with its `Retry-After` header)."""
    out: dict[int | str, dict[str, Any]] = {}
    for code in codes:
        entry: dict[str, Any] = {"model": ErrorOut, "description": DESCRIPTIONS[code]}
        if code == 429:
            entry["headers"] = RETRY_AFTER
        out[code] = entry
    return out


def _describe(err: dict[str, Any]) -> FieldError:
    return FieldError(
        loc=[p if isinstance(p, int) else str(p) for p in err.get("loc", ())],
        msg=str(err.get("msg", "")),
        type=str(err.get("type", "")),
    )


def validation_error_body(exc: RequestValidationError) -> ErrorOut:
    """The 422 body: one line per problem in `detail` (never the submitted value, which
    may be a password), and the problems themselves in `errors`."""
    problems = [_describe(e) for e in exc.errors()]
    lines = [f"{'.'.join(str(p) for p in e.loc) or 'request'}: {e.msg}" for e in problems]
    return ErrorOut(detail="; ".join(lines) or "invalid request", errors=problems)


def http_routes(routes: Sequence[BaseRoute]) -> Iterator[Any]:
    """Every route of an app, those of included routers too, with their full paths
    (FastAPI's `RouteContext`s where it has them: `path_format`, `methods`, `matches`,
    `original_route`)."""
    try:
        from fastapi.routing import iter_route_contexts
    except ImportError:  # a FastAPI that lists included routes flat in app.routes
        yield from routes
        return
    yield from iter_route_contexts(routes)


def allowed_methods(request: Request) -> list[str]:
    """Every method some route of this app answers at the request's path."""
    methods: set[str] = set()
    for route in http_routes(request.app.router.routes):
        if route.methods:
            match, _ = route.matches(request.scope)
            if match is not Match.NONE:
                methods |= set(route.methods)
    return sorted(methods)


async def _http_error(request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, StarletteHTTPException)
    detail = exc.detail if isinstance(exc.detail, str) else str(exc.detail)
    headers = dict(exc.headers or {})
    if exc.status_code == 405:
        headers["Allow"] = ", ".join(allowed_methods(request))
    return JSONResponse(
        ErrorOut(detail=detail).model_dump(), status_code=exc.status_code, headers=headers
    )


async def _validation_error(request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, RequestValidationError)
    return JSONResponse(validation_error_body(exc).model_dump(), status_code=422)


def install_error_handlers(app: FastAPI) -> None:
    """Make every error of `app` an `ErrorOut`."""
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(RequestValidationError, _validation_error)

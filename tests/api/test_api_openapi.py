"""The OpenAPI schema is honest about authentication and errors: bearer security on
every route but the open two, every error response an `ErrorOut`, and what the app
really sends for a validation error, an unknown path and an unknown method matches."""

from __future__ import annotations

from api_helpers import Api


def test_security_and_error_responses_are_declared(api: Api) -> None:
    schema = api.client.get("/api/openapi.json", headers=api.admin).json()
    assert schema["components"]["securitySchemes"] == {
        "bearer": {
            "type": "http",
            "scheme": "bearer",
            "description": "the token from POST /api/auth/login",
        }
    }
    assert "HTTPValidationError" not in schema["components"]["schemas"]
    operations = 0
    for path, methods in schema["paths"].items():
        for method, op in methods.items():
            operations += 1
            open_route = (method, path) in (("get", "/api/health"), ("post", "/api/auth/login"))
            assert (op.get("security") is None) == open_route, f"{method} {path}"
            if not open_route:
                assert "401" in op["responses"], f"{method} {path}"
            for code, response in op["responses"].items():
                if code.startswith(("4", "5")):
                    ref = response["content"]["application/json"]["schema"]["$ref"]
                    assert ref == "#/components/schemas/ErrorOut", f"{method} {path} {code}"
    assert operations >= 29
    login = schema["paths"]["/api/auth/login"]["post"]["responses"]
    assert login["429"]["headers"]["Retry-After"]["schema"]["type"] == "integer"
    # A plain-string path parameter cannot fail validation: no 422 promised there.
    assert "422" not in schema["paths"]["/api/streams/{name}"]["get"]["responses"]
    assert "422" in schema["paths"]["/api/commands"]["get"]["responses"]


def test_error_bodies_have_one_shape(api: Api) -> None:
    c = api.client
    bad = c.get("/api/commands?limit=0", headers=api.admin)
    assert bad.status_code == 422
    body = bad.json()
    assert isinstance(body["detail"], str) and body["detail"].startswith("query.limit:")
    assert body["errors"] == [
        {
            "loc": ["query", "limit"],
            "msg": "Input should be greater than or equal to 1",
            "type": "greater_than_equal",
        }
    ]
    garbled = c.post(
        "/api/training/runs",
        content=b"{not json",
        headers={**api.admin, "content-type": "application/json"},
    )
    assert garbled.status_code == 422 and garbled.json()["errors"][0]["type"] == "json_invalid"
    missing = c.get("/api/no-such-thing", headers=api.admin)
    assert missing.status_code == 404 and missing.json() == {"detail": "Not Found", "errors": []}
    wrong = c.delete("/api/users", headers=api.admin)
    assert wrong.status_code == 405 and wrong.headers["allow"] == "GET, POST"
    assert wrong.json()["detail"] == "Method Not Allowed"
    unauthorised = c.get("/api/streams")
    assert unauthorised.status_code == 401 and unauthorised.headers["www-authenticate"] == "Bearer"
    assert set(unauthorised.json()) == {"detail", "errors"}

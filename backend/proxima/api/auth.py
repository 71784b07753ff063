"""Session tokens on requests: `Authorization: Bearer TOKEN` for HTTP; for the WebSocket
(where browsers cannot set headers) the token rides as the second subprotocol,
`new WebSocket(url, ["proxima", TOKEN])`, so it never appears in a URL or a log.

The 3D view (`/viser/`, proxied to viser) is loaded by an iframe and by viser's own
client, which can send neither a header nor our subprotocol, and drops any query string
from its WebSocket URL: it gets the session token as a cookie instead, `proxima_view`,
set at login (and again by `POST /api/auth/view-cookie`), cleared at logout. The cookie
is HttpOnly (no script reads it), SameSite=Strict (no other site's page sends it),
Secure under HTTPS, and its Path is /viser, so the API never sees it and never accepts
it: the API stays bearer-only, out of reach of cross-site requests.
"""

from __future__ import annotations

from dataclasses import dataclass

from starlette.requests import HTTPConnection
from starlette.responses import Response

from proxima.settings import ServerSettings
from proxima.store.users import Role, User

WS_SUBPROTOCOL = "proxima"
VIEW_COOKIE = "proxima_view"
VIEW_PATH = "/viser"


@dataclass(frozen=True)
class AuthUser:
    """The logged-in user of one request."""

    id: int
    username: str
    role: Role
    must_change_password: bool
    token: str

    @classmethod
    def of(cls, user: User, token: str) -> AuthUser:
        return cls(
            id=user.id,
            username=user.username,
            role=Role(user.role),
            must_change_password=user.must_change_password,
            token=token,
        )

    @property
    def is_supervisor(self) -> bool:
        return self.role is Role.SUPERVISOR


def token_from(conn: HTTPConnection) -> str | None:
    """The session token a request or WebSocket handshake carries, if any."""
    header = conn.headers.get("authorization", "")
    scheme, _, value = header.partition(" ")
    if scheme.lower() == "bearer" and value.strip():
        return value.strip()
    protocols = [p.strip() for p in conn.headers.get("sec-websocket-protocol", "").split(",")]
    if len(protocols) == 2 and protocols[0] == WS_SUBPROTOCOL and protocols[1]:
        return protocols[1]
    return None


def set_view_cookie(response: Response, token: str, server: ServerSettings) -> None:
    """Let this browser open the 3D view with the session `token` (see the module doc)."""
    response.set_cookie(
        VIEW_COOKIE,
        token,
        max_age=int(server.session_ttl_s),
        path=VIEW_PATH,
        secure=server.tls,
        httponly=True,
        samesite="strict",
    )


def clear_view_cookie(response: Response, server: ServerSettings) -> None:
    response.delete_cookie(
        VIEW_COOKIE, path=VIEW_PATH, secure=server.tls, httponly=True, samesite="strict"
    )

"""Session tokens on requests: `Authorization: Bearer TOKEN` for HTTP; for the WebSocket
(where browsers cannot set headers) the token rides as the second subprotocol,
`new WebSocket(url, ["proxima", TOKEN])`, so it never appears in a URL or a log."""

from __future__ import annotations

from dataclasses import dataclass

from starlette.requests import HTTPConnection

from proxima.store.users import Role, User

WS_SUBPROTOCOL = "proxima"


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

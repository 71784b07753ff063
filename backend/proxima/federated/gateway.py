"""The Fleet-only gateway: what the drones reach on the ground station's network.

In flwr 1.41 and 1.42 the SuperLink serves three APIs on one HTTPS port: the Fleet API (what
SuperNodes call), the Control API (`flwr run`, `flwr supernode register`: submit code to
run, admit a SuperNode key) and the Runtime API (the ServerApp's). The open-source
SuperLink authenticates no Control API caller, so whoever reaches that port could
register a key of their own or run any code on the ground station. The SuperLink
therefore binds 127.0.0.1, and this gateway listens on the fleet address with the same
TLS certificate, passes `POST /v1/fleet/...` through unchanged (body and headers, which
carry the SuperNode's public key, signature and timestamp, so Flower's SuperNode
authentication still decides) and answers 404 for everything else.

Run by `LocalFederation` as its own process:

    python -m proxima.federated.gateway --listen 0.0.0.0:9092 --upstream 127.0.0.1:9093 \\
        --ca-certfile ca.crt --certfile server.pem --keyfile server.key
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import ssl
from collections.abc import AsyncIterator
from pathlib import Path

import httpx
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route

from proxima.federated.settings import split_address

log = logging.getLogger("proxima.federated.gateway")

FLEET_PREFIX = "/v1/fleet/"
# Hop-by-hop headers (RFC 9110 7.6.1) and those the HTTP client sets itself.
_DROP = frozenset(
    {"connection", "keep-alive", "proxy-connection", "te", "trailer", "transfer-encoding",
     "upgrade", "host", "content-length", "accept-encoding"}
)  # fmt: skip
MAX_BODY = 512 * 1024 * 1024  # a model's arrays travel as objects; far below this


def create_app(upstream: str, ca_certfile: Path, timeout_s: float = 600.0) -> Starlette:
    """The gateway's ASGI app, forwarding Fleet API calls to `upstream` (HOST:PORT) over
    TLS verified against `ca_certfile`."""
    context = ssl.create_default_context(cafile=str(ca_certfile))
    client = httpx.AsyncClient(
        base_url=f"https://{upstream}", verify=context, timeout=timeout_s, http2=False
    )

    async def fleet(request: Request) -> Response:
        body = await request.body()
        if len(body) > MAX_BODY:
            return JSONResponse({"detail": "request body too large"}, status_code=413)
        headers = {k: v for k, v in request.headers.items() if k.lower() not in _DROP}
        try:
            res = await client.post(request.url.path, content=body, headers=headers)
        except httpx.HTTPError as exc:
            log.warning("SuperLink %s unreachable: %s", upstream, exc)
            return JSONResponse({"detail": "SuperLink unreachable"}, status_code=502)
        out = {k: v for k, v in res.headers.items() if k.lower() not in _DROP}
        out.pop("content-encoding", None)  # httpx has decoded the body already
        return Response(res.content, status_code=res.status_code, headers=out)

    async def refuse(request: Request) -> Response:
        log.warning("refused %s %s from %s", request.method, request.url.path,
                    request.client.host if request.client else "?")  # fmt: skip
        return JSONResponse({"detail": "only the Fleet API is served here"}, status_code=404)

    @contextlib.asynccontextmanager
    async def lifespan(_app: Starlette) -> AsyncIterator[None]:
        yield
        await client.aclose()

    methods = ["GET", "POST", "PUT", "PATCH", "DELETE", "HEAD", "OPTIONS"]
    return Starlette(
        routes=[
            Route(FLEET_PREFIX + "{rpc:str}", fleet, methods=["POST"]),
            Route("/{path:path}", refuse, methods=methods),
        ],
        lifespan=lifespan,
    )


def main(argv: list[str] | None = None) -> None:
    """`python -m proxima.federated.gateway`: serve the gateway over TLS."""
    import uvicorn

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--listen", required=True, help="HOST:PORT the drones dial")
    ap.add_argument("--upstream", required=True, help="the SuperLink's HOST:PORT (loopback)")
    ap.add_argument("--ca-certfile", type=Path, required=True)
    ap.add_argument("--certfile", type=Path, required=True)
    ap.add_argument("--keyfile", type=Path, required=True)
    args = ap.parse_args(argv)
    host, port = split_address(args.listen)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")
    logging.getLogger("httpx").setLevel(logging.WARNING)  # not a line per heartbeat
    app = create_app(args.upstream, args.ca_certfile)
    uvicorn.run(app, host=host, port=port, ssl_certfile=str(args.certfile),
                ssl_keyfile=str(args.keyfile), log_level="warning", access_log=False)  # fmt: skip


if __name__ == "__main__":
    main()

"""Running the console app with uvicorn: in the foreground (`proxima serve`) or on a
background thread (tests, benchmarks, the demo), always bound to a host you choose
(127.0.0.1 by default), over HTTPS when the settings name a certificate and key.

Stopping on a signal: uvicorn's own handling re-raises SIGINT/SIGTERM once it has shut
down, which kills the process before any `finally` runs, and ignores SIGHUP (whose
default action kills at once). `StopSignals` replaces both: SIGINT, SIGTERM and SIGHUP
only ask to stop (a second one also stops waiting for open connections), and stay
handled until the caller has closed everything it started (Flower processes, drone
links, the 3D view).
"""

from __future__ import annotations

import contextlib
import logging
import signal
import threading
import time
from collections.abc import Callable, Generator
from types import FrameType, TracebackType

import uvicorn
from fastapi import FastAPI

from proxima.settings import ServerSettings

log = logging.getLogger(__name__)

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
GRACEFUL_SHUTDOWN_S = 5  # open WebSockets get this long to close before they are cut


def _config(app: FastAPI, host: str, port: int, server: ServerSettings | None) -> uvicorn.Config:
    tls = server is not None and server.tls
    return uvicorn.Config(
        app,
        host=host,
        port=port,
        log_level="warning",
        lifespan="on",
        # The sans-I/O implementation: uvicorn's default one sits on websockets' legacy
        # API, deprecated since websockets 14 and to be removed.
        ws="websockets-sansio",
        ws_ping_interval=20,
        timeout_graceful_shutdown=GRACEFUL_SHUTDOWN_S,
        ssl_certfile=server.tls_certfile if tls and server else None,
        ssl_keyfile=server.tls_keyfile if tls and server else None,
    )


class StopSignals:
    """While entered, SIGINT, SIGTERM and SIGHUP call `on_stop` (from the main thread)
    instead of killing the process; `received` is the first one (None if none came).
    Previous handlers come back on exit."""

    def __init__(self, on_stop: Callable[[int], None] | None = None) -> None:
        self.on_stop = on_stop
        self.received: int | None = None
        self._previous: dict[int, object] = {}

    def _handle(self, signum: int, _frame: FrameType | None) -> None:
        if self.received is None:
            self.received = signum
            log.warning("%s received: stopping", signal.Signals(signum).name)
        if self.on_stop is not None:
            self.on_stop(signum)

    def __enter__(self) -> StopSignals:
        for sig in STOP_SIGNALS:
            self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)  # type: ignore[arg-type]


class _Uvicorn(uvicorn.Server):
    """uvicorn without its own signal handling (see the module doc)."""

    @contextlib.contextmanager
    def capture_signals(self) -> Generator[None, None, None]:
        yield


class ForegroundServer:
    """uvicorn in the calling (main) thread; `run()` returns when `stop()` is called,
    e.g. by `StopSignals`, after a graceful shutdown."""

    def __init__(
        self, app: FastAPI, host: str, port: int, server: ServerSettings | None = None
    ) -> None:
        self._server = _Uvicorn(_config(app, host, port, server))

    def run(self) -> None:
        """Serve until stopped.

        Raises:
            SystemExit: uvicorn could not start (e.g. the port is taken; it logs why).
        """
        self._server.run()

    def stop(self, _signum: int = 0) -> None:
        """Ask to stop; a second call stops waiting for open connections too."""
        if self._server.should_exit:
            self._server.force_exit = True
        self._server.should_exit = True


class BackgroundServer:
    """uvicorn on its own thread; `port=0` picks a free port (read `.port` after start).

    Raises:
        RuntimeError: (start) the server did not come up within the timeout.
    """

    def __init__(
        self,
        app: FastAPI,
        host: str = "127.0.0.1",
        port: int = 0,
        server: ServerSettings | None = None,
    ) -> None:
        self.app = app
        self.host = host
        self.scheme = "https" if server is not None and server.tls else "http"
        self._server = uvicorn.Server(_config(app, host, port, server))
        self._thread = threading.Thread(target=self._server.run, name="console", daemon=True)
        self.port = port

    def start(self, timeout: float = 15.0) -> BackgroundServer:
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self._server.started:
            if not self._thread.is_alive() or time.monotonic() > deadline:
                raise RuntimeError(f"console server did not start on {self.host}:{self.port}")
            time.sleep(0.02)
        sockets = self._server.servers[0].sockets
        self.port = sockets[0].getsockname()[1]
        return self

    @property
    def url(self) -> str:
        return f"{self.scheme}://{self.host}:{self.port}"

    def stop(self, timeout: float = 10.0) -> None:
        self._server.should_exit = True
        self._thread.join(timeout)

    def __enter__(self) -> BackgroundServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

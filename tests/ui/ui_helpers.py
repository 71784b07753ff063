"""Helpers for the browser tests: Chromium flags, users, a console server on a thread
(so a test can drive its bus), logging in, screenshots (into runs/screenshots/, which git
ignores; `make screenshots` copies them over docs/screenshots/)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from proxima.api.runtime import ConsoleRuntime, build_runtime
from proxima.api.server import BackgroundServer
from proxima.settings import Settings
from proxima.store.users import Role, create_user

REPO = Path(__file__).resolve().parents[2]
SCREENSHOTS = REPO / "runs" / "screenshots"
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-background-networking",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-component-update",
    "--disable-sync",
]
ADMIN = ("chief", "correct-horse-battery")
VIEWER = ("watcher", "viewer-password-42")


def laser_clip(name: str) -> Path:
    """A LASER clip by its gesture_view suffix, e.g. `move_to_left_f`."""
    from proxima.gesture.data_source import resolve_laser_dir

    root = Path(resolve_laser_dir(None))
    matches = sorted(root.glob(f"DJI_*_{name}.MP4.csv"))
    assert matches, f"no LASER clip *_{name}.MP4.csv in {root}"
    return matches[0]


@dataclass
class Console:
    runtime: ConsoleRuntime
    server: BackgroundServer

    @property
    def url(self) -> str:
        return self.server.url

    @property
    def bus(self):  # type: ignore[no-untyped-def]
        return self.runtime.bus

    def close(self) -> None:
        self.server.stop()
        self.runtime.close()


def own_server(tmp: Path) -> dict[str, Any]:
    """`[server]` for a console with its own database and (empty) models folder under
    `tmp`, and no 3D view."""
    return {
        "db_path": str(tmp / "c.db"),
        "models_dir": str(tmp / "models"),
        "viser_enabled": False,
    }


def start_console(
    tmp: Path,
    *,
    with_engine: bool = False,
    with_drones: bool = False,
    with_view: bool = False,
    **overrides: Any,
) -> Console:
    """A console on 127.0.0.1 with a supervisor and a viewer; the live engine, the drone
    links and the 3D view run only when asked (and configured)."""
    if not (REPO / "static" / "index.html").is_file():
        pytest.fail("frontend not built: run `make frontend` (npm run build in frontend/)")
    base: dict[str, Any] = {
        "admin_user": ADMIN[0],
        "admin_password": ADMIN[1],
        "server": {"db_path": str(tmp / "console.db"), "viser_port": 0},
    }
    base.update(overrides)
    settings = Settings.load(config=None, **base)
    runtime = build_runtime(settings, engine=with_engine, drones=with_drones, view=with_view)
    with runtime.app.state.console.sessions() as db:
        create_user(db, VIEWER[0], VIEWER[1], Role.VIEWER)
    return Console(runtime, BackgroundServer(runtime.app).start())


def login(page, url: str, user: tuple[str, str] = ADMIN) -> None:  # type: ignore[no-untyped-def]
    page.goto(url + "/")
    page.fill("#login-form input[name=username]", user[0])
    page.fill("#login-form input[name=password]", user[1])
    page.click("#login-form button[type=submit]")
    page.wait_for_selector("#topbar:not([hidden])")
    page.wait_for_selector("#conn.ok")


def screenshot(page, name: str) -> Path:  # type: ignore[no-untyped-def]
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def wait_for(predicate, timeout: float = 15.0, what: str = "condition", page=None):  # type: ignore[no-untyped-def]
    """Poll `predicate` until it returns something truthy; fail naming `what`. With
    `page`, wait through the page so Playwright's callbacks (routes, events) run."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        if page is None:
            time.sleep(0.1)
        else:
            page.wait_for_timeout(100)
    raise AssertionError(f"timed out waiting for {what}")

"""Browser tests of the console: a real server on 127.0.0.1 (uvicorn on a thread, so the
test can drive its event bus), Debian's Chromium driven by Playwright, streams replayed
from the LASER dataset. Screenshots go to docs/screenshots/."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from proxima.api import create_app
from proxima.api.server import BackgroundServer
from proxima.events import EventBus
from proxima.settings import Settings
from proxima.store.users import Role, create_user

REPO = Path(__file__).resolve().parents[2]
SCREENSHOTS = REPO / "docs" / "screenshots"
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


def laser_dir() -> Path:
    from proxima.gesture.data_source import resolve_laser_dir

    return Path(resolve_laser_dir(None))


def clip(name: str) -> Path:
    """A LASER clip by its gesture_view suffix, e.g. `move_to_left_f`."""
    matches = sorted(laser_dir().glob(f"DJI_*_{name}.MP4.csv"))
    assert matches, f"no LASER clip *_{name}.MP4.csv in {laser_dir()}"
    return matches[0]


@pytest.fixture(scope="session")
def browser():
    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} missing: apt-get install -y chromium (see .ci/run)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        yield b
        b.close()


@dataclass
class Console:
    url: str
    bus: EventBus
    settings: Settings
    app: object
    server: BackgroundServer


def make_console(tmp: Path, **overrides: object) -> tuple[Console, BackgroundServer]:
    if not (REPO / "static" / "index.html").is_file():
        pytest.fail("frontend not built: run `make frontend` (npm run build in frontend/)")
    settings = Settings.load(
        config=None,
        admin_user=ADMIN[0],
        admin_password=ADMIN[1],
        server={"db_path": str(tmp / "console.db"), "viser_enabled": False},
        **overrides,
    )
    bus = EventBus()
    app = create_app(settings, bus)
    with app.state.console.sessions() as db:
        create_user(db, VIEWER[0], VIEWER[1], Role.VIEWER)
    server = BackgroundServer(app).start()
    return Console(server.url, bus, settings, app, server), server


@pytest.fixture
def page(browser) -> Iterator[object]:
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    pg = context.new_page()
    pg.set_default_timeout(15000)
    yield pg
    context.close()


def login(page, url: str, user: tuple[str, str] = ADMIN) -> None:
    page.goto(url + "/")
    page.fill("#login-form input[name=username]", user[0])
    page.fill("#login-form input[name=password]", user[1])
    page.click("#login-form button[type=submit]")
    page.wait_for_selector("#topbar:not([hidden])")
    page.wait_for_selector("#conn.ok")


def screenshot(page, name: str) -> Path:
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


@pytest.fixture
def tmp_db_dir(tmp_path: Path) -> Iterator[Path]:
    yield tmp_path
    shutil.rmtree(tmp_path, ignore_errors=True)

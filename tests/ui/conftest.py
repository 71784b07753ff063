"""Browser tests of the console: a real server on 127.0.0.1 (uvicorn on a thread, so the
test can drive its event bus), Debian's Chromium driven by Playwright, streams replayed
from the LASER dataset. Screenshots go to runs/screenshots/ (`make screenshots` refreshes
the docs' copies)."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from ui_helpers import CHROMIUM, CHROMIUM_ARGS


@pytest.fixture(scope="session")
def browser() -> Iterator[object]:
    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} missing: apt-get install -y chromium (see .ci/run)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser) -> Iterator[object]:  # type: ignore[no-untyped-def]
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    pg = context.new_page()
    # A bound on every wait, not a speed check: under `make test` the browser shares two
    # cores with the other pytest-xdist worker's training, and software WebGL, a
    # screenshot or a resume through the drone link have taken over 15 s there.
    pg.set_default_timeout(45000)
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    yield pg
    context.close()
    assert not errors, f"JavaScript errors in the page: {errors}"

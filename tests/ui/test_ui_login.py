"""Logging in to the console in a real browser."""

from __future__ import annotations

from pathlib import Path

from ui_helpers import ADMIN, VIEWER, login, screenshot, start_console


def test_login_and_logout(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    console = start_console(tmp_path)
    try:
        page.goto(console.url + "/")
        page.wait_for_selector("#login-form")
        screenshot(page, "login")
        page.fill("#login-form input[name=username]", ADMIN[0])
        page.fill("#login-form input[name=password]", "not-the-password")
        page.click("#login-form button[type=submit]")
        page.wait_for_selector("#login-error:has-text('wrong user name or password')")
        assert page.is_hidden("#topbar")
        login(page, console.url, VIEWER)
        assert page.inner_text("#whoami") == f"{VIEWER[0]} (viewer)"
        page.click("#logout")
        page.wait_for_selector("#login-form:not([hidden])")
        login(page, console.url, ADMIN)
        assert page.inner_text("#whoami") == f"{ADMIN[0]} (supervisor)"
    finally:
        console.close()

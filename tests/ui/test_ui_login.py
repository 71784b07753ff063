"""Logging in to the console in a real browser."""

from __future__ import annotations

from pathlib import Path

from ui_helpers import ADMIN, VIEWER, login, screenshot, start_console, wait_for


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


def test_throttled_login_counts_down_then_lets_in(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    console = start_console(
        tmp_path,
        server={
            "db_path": str(tmp_path / "console.db"),
            "login_free_failures": 1,
            "login_backoff_s": 3.0,
            "login_backoff_max_s": 3.0,
        },
    )
    try:
        page.goto(console.url + "/")
        page.fill("#login-form input[name=username]", ADMIN[0])
        for _ in range(2):  # the second failure starts a 3 s block
            page.fill("#login-form input[name=password]", "not-the-password")
            page.click("#login-form button[type=submit]")
            page.wait_for_selector("#login-error:has-text('wrong user name or password')")
            page.evaluate("document.querySelector('#login-error').textContent = ''")
        page.fill("#login-form input[name=password]", ADMIN[1])
        page.click("#login-form button[type=submit]")
        page.wait_for_selector("#login-error:has-text('Too many failed logins: try again in')")
        assert page.is_disabled("#login-form button[type=submit]")
        screenshot(page, "login-throttled")
        # The countdown ends, the button comes back, and the right password works.
        page.wait_for_selector("#login-form button[type=submit]:enabled", timeout=10000)
        assert page.inner_text("#login-error") == ""
        page.click("#login-form button[type=submit]")
        page.wait_for_selector("#topbar:not([hidden])")
    finally:
        console.close()


def test_reload_during_logout_lands_on_the_login_form(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """The page reloads while the logout request is still on its way (CI saw it: a test
    logged out and navigated at once). The session being closed must not come back."""
    console = start_console(tmp_path)
    held: list = []  # type: ignore[type-arg]
    try:
        login(page, console.url)
        page.route("**/api/auth/logout", lambda route: held.append(route))
        page.click("#logout")
        wait_for(lambda: held, 5, "the logout request", page)
        # The server has not answered yet: the token is already forgotten.
        assert page.evaluate("sessionStorage.getItem('proxima.token')") is None
        page.reload()
        page.wait_for_selector("#login-form:not([hidden])")
        page.wait_for_timeout(500)  # a restored session would show the console by now
        assert page.is_hidden("#topbar")
        login(page, console.url)
        assert page.inner_text("#whoami") == f"{ADMIN[0]} (supervisor)"
    finally:
        page.unroute_all(behavior="ignoreErrors")
        console.close()

"""A page left before its requests answer: the Training and Labelling pages load their
tables with requests that can come back after the operator has moved on to
another page. The answers must be dropped, not thrown at a page that is gone (the
`page` fixture fails the test on any JavaScript error)."""

from __future__ import annotations

from pathlib import Path

import pytest
from ui_helpers import login, own_server, start_console, wait_for


@pytest.mark.parametrize("name", ["training", "labelling"])
def test_answers_after_the_page_was_left_are_dropped(  # type: ignore[no-untyped-def]
    page, tmp_path: Path, name: str
) -> None:
    console = start_console(
        tmp_path,
        server=own_server(tmp_path),
        training={"enabled": False},
    )
    held: list = []  # type: ignore[type-arg]
    holding = [True]

    def hold(route) -> None:  # type: ignore[no-untyped-def]
        if holding[0]:
            held.append(route)
        else:
            route.continue_()

    try:
        login(page, console.url)
        page.route("**/api/**", hold)
        page.click(f"nav a[data-page={name}]")
        wait_for(lambda: held, 5, f"the {name} page to ask the server", page)
        holding[0] = False
        page.click("nav a[data-page=live]")
        page.wait_for_selector("nav a[data-page=live].active")
        # Only now do the held requests reach the server and their answers the page.
        finished: list = []  # type: ignore[type-arg]
        page.on("requestfinished", lambda r: finished.append(r))
        for route in held:
            route.continue_()
        requests = {r.request for r in held}
        wait_for(lambda: requests <= set(finished), 10, "the held requests to finish", page)
        page.wait_for_timeout(300)  # the pages' code after each answer
        assert page.is_visible("nav a[data-page=live].active")
    finally:
        console.close()

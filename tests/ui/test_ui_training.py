"""The Training page: a viewer who tries to start a federated run gets 403."""

from __future__ import annotations

from pathlib import Path

from ui_helpers import VIEWER, login, screenshot, start_console


def test_viewer_gets_403_on_starting_a_run(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    console = start_console(tmp_path)
    try:
        login(page, console.url, VIEWER)
        page.click("nav a[data-page=training]")
        page.wait_for_selector("form.start-run")
        with page.expect_response(
            lambda r: r.url.endswith("/api/training/runs") and r.request.method == "POST"
        ) as response:
            page.click("form.start-run button.start")
        assert response.value.status == 403
        page.wait_for_selector(".train-status.error:has-text('Forbidden')")
        assert "viewer" in page.inner_text(".train-status")
        screenshot(page, "training-viewer-403")
    finally:
        console.close()

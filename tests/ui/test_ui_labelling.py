"""Labelling in a real browser: record frames of a replayed LASER stream after a
countdown, review them as a skeleton playback, keep them with a gesture, find the
sample listed (and stored for that stream's drone)."""

from __future__ import annotations

from pathlib import Path

from ui_helpers import laser_clip, login, screenshot, start_console

from proxima.api.feed import ReplayPoseFeed
from proxima.store.samples import kept_samples


def test_record_label_and_list(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    uri = f"replay:{laser_clip('land_direction_f')}@30"
    console = start_console(
        tmp_path,
        streams=[{"name": "front", "uri": uri, "drone": "main"}],
        drones=[{"name": "main", "connection": "udpin:127.0.0.1:14550"}],
    )
    feed = ReplayPoseFeed(console.bus, {"front": uri}).start()
    try:
        login(page, console.url)
        page.click("nav a[data-page=labelling]")
        # An empty list says so (issue 26, finding 9); the chosen stream previews live.
        page.wait_for_selector("table.samples .empty-list:has-text('No samples yet')")
        page.select_option("select.stream", "front")
        page.wait_for_function("() => document.querySelector('canvas.preview').dataset.poseT")
        page.fill("input.frames", "24")  # under the 30-frame window: padded
        page.fill("input.countdown", "1.5")
        # A wrong label on purpose: the model's reading must disagree and say so.
        page.select_option("select.gesture", "move_upward")
        page.click("button.record")
        page.wait_for_selector(".rec-status.countdown")  # the countdown is shown first
        page.wait_for_selector(".review-box:not([hidden])")
        title = page.inner_text(".review-title")
        assert "24 frames of front for main (pending)" in title
        # The review canvas plays the recorded skeleton.
        first = page.get_attribute("canvas.review", "data-frame")
        page.wait_for_function(
            "f => document.querySelector('canvas.review').dataset.frame !== f", arg=first
        )
        sample_id = int(title.split(":")[0].split()[-1])
        token = page.evaluate("() => sessionStorage.getItem('proxima.token')")
        import httpx

        read = httpx.get(
            f"{console.url}/api/samples/{sample_id}/reading",
            headers={"Authorization": f"Bearer {token}"},
            timeout=60,
        ).json()
        assert read["frames"] == 24 and read["padded"] and read["gesture"] != "move_upward", read
        page.wait_for_selector(f".reading.warn:has-text('reads this as {read['gesture']}')")
        assert "not move_upward" in page.inner_text(".reading")
        page.select_option("select.gesture", "land_direction")
        if read["gesture"] == "land_direction":
            page.wait_for_selector(".reading.ok:has-text('reads this as land_direction')")
        else:
            page.wait_for_selector(".reading.warn:has-text('not land_direction')")
        screenshot(page, "labelling")
        page.click("button.keep")
        row = page.wait_for_selector("table.samples tbody tr.st-kept")
        assert row.query_selector(".label").inner_text() == "land_direction"
        cells = [c.inner_text() for c in row.query_selector_all("td")]
        assert cells[2:] == ["front", "main", "land_direction", "kept", "24"]
        assert page.is_disabled("button.keep")  # kept once is kept
        # The gesture chosen stays chosen after leaving the page.
        page.click("nav a[data-page=live]")
        page.click("nav a[data-page=labelling]")
        # The page mounts on the hash change, after the click returns.
        page.wait_for_selector("select.gesture")
        assert page.eval_on_selector("select.gesture", "s => s.value") == "land_direction"
        with console.runtime.app.state.console.sessions() as db:
            kept = kept_samples(db, "main")
        assert [(k.label, k.xyz.shape) for k in kept] == [("land_direction", (24, 33, 3))]
    finally:
        feed.stop()
        console.close()

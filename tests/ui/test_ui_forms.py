"""Forms check in the browser with the server's own bounds and say what is wrong in a
sentence (issue 26, finding 10): rounds 0, empty or text; minimum clients above the
federation's drones; recording frames 0 or 100,000 and a negative countdown. Nothing
is sent while a field is wrong, and the message clears once the field is corrected."""

from __future__ import annotations

from pathlib import Path

from ui_helpers import login, own_server, screenshot, start_console


def test_forms_refuse_bad_values_with_sentences(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    console = start_console(
        tmp_path,
        server=own_server(tmp_path),
    )
    posts: list[str] = []
    page.on("request", lambda r: posts.append(r.url) if r.method == "POST" else None)
    try:
        assert console.runtime.training is not None, console.runtime.notes
        fleet = len(console.runtime.training.clients)
        login(page, console.url)
        page.click("nav a[data-page=training]")
        status = ".train-status"
        rounds = "form.start-run input[name=rounds]"
        for value, says in (("0", "0 is too small"), ("", "it is empty"), ("1000000", "too large"),
                            ("2.5", "is not whole")):  # fmt: skip
            page.fill(rounds, value)
            page.click("form.start-run button.start")
            text = page.inner_text(status)
            assert text.startswith("Rounds must be a whole number from 1 to 500") and says in text
            assert "{" not in text  # a sentence, not JSON
        page.fill(rounds, "1")
        assert page.inner_text(status) == ""  # cleared by the correction
        page.fill("form.start-run input[name=min_clients]", str(fleet + 2))
        page.click("form.start-run button.start")
        assert f"the federation has {fleet} drones" in page.inner_text(status)
        screenshot(page, "forms-training")
        assert not [u for u in posts if u.endswith("/api/training/runs")]

        page.click("nav a[data-page=labelling]")
        page.fill("input.frames", "0")
        page.fill("input.countdown", "-3")
        page.click("button.record")
        text = page.inner_text(".rec-status")
        assert "Frames must be a whole number from 1 to 900" in text
        assert "Countdown must be a number from 0 to 30" in text
        page.fill("input.frames", "100000")
        page.fill("input.countdown", "3")
        assert page.inner_text(".rec-status") == ""
        page.click("button.record")
        assert "100000 is too large" in page.inner_text(".rec-status")
        assert not [u for u in posts if u.endswith("/api/samples/recordings")]
    finally:
        console.close()

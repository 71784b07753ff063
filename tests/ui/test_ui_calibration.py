"""Calibration in a real browser: a stream replayed through the live engine, two gestures
walked through (prompt, countdown, record, the model's reading, a warning and a redo),
training, the before/after figures on the held-out parts, and promotion for that stream
only behind a confirmation naming both models."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from ui_helpers import ADMIN, laser_clip, login, screenshot, start_console

from proxima.ingest import read_landmark_csv
from proxima.ingest.landmark_csv import write_landmark_csv
from proxima.store.samples import kept_samples


def long_replay(path: Path, names: list[str]) -> Path:
    """LASER clips one after the other as one replay file, so the operator stays in view
    for every take."""
    tracks = [read_landmark_csv(laser_clip(n)) for n in names]
    frames, offset = [], 0
    for t in tracks:
        frames.append(t.frames - t.frames[0] + 1 + offset)
        offset = int(frames[-1][-1]) + 15
    write_landmark_csv(
        path,
        np.concatenate(frames),
        np.concatenate([t.xyz for t in tracks]),
        np.concatenate([t.visibility for t in tracks]),
    )
    return path


def test_calibrate_a_camera_and_promote_for_it(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    replay = long_replay(tmp_path / "front.csv", ["move_downward_f", "hover_f", "all_clear_f"])
    models = tmp_path / "models"
    console = start_console(
        tmp_path,
        with_engine=True,
        streams=[
            {"name": "front", "uri": f"replay:{replay}@30", "drone": "main"},
            {"name": "left", "uri": f"replay:{laser_clip('hover_l')}@30", "drone": "second"},
        ],
        server={"db_path": str(tmp_path / "console.db"), "viser_port": 0,
                "models_dir": str(models)},
    )  # fmt: skip
    engine = console.runtime.engine
    assert engine is not None, console.runtime.notes
    try:
        login(page, console.url)
        page.click("nav a[data-page=calibration]")
        page.select_option("select.stream", "front")
        page.wait_for_function("() => document.querySelector('canvas.preview').dataset.poseT")
        # The form checks the server's bounds before sending: a take needs 180 frames.
        page.fill("input.frames", "90")
        page.click("button.start-calibration")
        page.wait_for_selector(".calib-status.error:has-text('from 180 to 900')")
        assert page.is_visible("input.frames.invalid")
        page.fill("input.frames", "180")
        page.fill("input.countdown", "1")
        page.fill("input.epochs", "3")
        page.click(".gesture-choices summary")
        for box in page.query_selector_all("input.gesture-choice"):
            if box.get_attribute("value") not in ("move_downward", "wave_off"):
                box.uncheck()
        page.click("button.start-calibration")
        page.wait_for_selector(".walk:not([hidden])")
        assert page.inner_text("ol.takes").split() == ["move_downward", "wave_off"]
        assert page.get_attribute(".prompt-gesture", "data-gesture") == "move_downward"
        assert page.inner_text(".prompt-description")  # a short description to follow

        # The stream performs move_downward: the reading agrees.
        page.click("button.record-take")
        page.wait_for_selector(".take-status.countdown")
        page.wait_for_selector(".take-status.rec")
        page.wait_for_selector(".take-reading.ok:has-text('reads this take as move_downward')")
        assert "1 of 2 takes" in page.inner_text(".walk-title")
        page.click("button.next-take")
        assert page.get_attribute(".prompt-gesture", "data-gesture") == "wave_off"
        # Prompted wave_off while the stream shows something else: a warning, then a redo.
        page.click("button.record-take")
        page.wait_for_selector(".take-reading.warn:has-text('not wave_off')")
        assert page.is_visible("ol.takes li.st-warn[data-gesture=wave_off]")
        screenshot(page, "calibration-takes")
        assert page.inner_text("button.record-take") == "Redo wave_off"
        first = page.inner_text(".take-status")
        page.click("button.record-take")
        page.wait_for_selector(".take-status.rec")
        page.wait_for_function(
            "f => { const s = document.querySelector('.take-status');"
            " return s.classList.contains('ok') && s.textContent !== f; }",
            arg=first,
            timeout=25000,
        )
        with console.runtime.app.state.console.sessions() as db:
            kept = kept_samples(db, "main")
        assert sorted(k.label for k in kept) == ["move_downward", "wave_off"]

        page.click("button.train")
        page.wait_for_selector(".train-status.ok:has-text('Trained')", timeout=90000)
        rows = page.query_selector_all("table.figures tbody tr")
        assert [r.get_attribute("data-gesture") for r in rows] == ["move_downward", "wave_off"]
        overall = page.query_selector("table.figures tfoot tr")
        assert overall.query_selector(".before").inner_text().endswith("%")
        assert overall.query_selector(".after").inner_text().endswith("%")
        assert "held-out" in page.inner_text(".figures-note")
        page.locator(".training-box").scroll_into_view_if_needed()
        screenshot(page, "calibration")

        left = engine.pipelines["left"].classifier
        front = engine.pipelines["front"].classifier
        page.click("button.promote-stream")
        question = page.inner_text(".promote-question")
        assert "calibration/front-" in question and "gesture-default.pt" in question
        assert "stream front only" in question
        if page.is_visible("textarea.override-reason"):  # worse on the held-out parts
            assert page.is_disabled("button.confirm-promote-stream")
            page.fill("textarea.override-reason", "field calibration")
        page.click("button.confirm-promote-stream")
        page.wait_for_selector(".train-status.ok:has-text('runs on front')")
        assert page.is_disabled("button.promote-stream")
        assert engine.pipelines["front"].classifier is not front
        assert engine.pipelines["left"].classifier is left
        promoter = console.runtime.promoter
        assert promoter is not None and set(promoter.stream_checkpoints()) == {"front"}
        assert ADMIN[0] in page.inner_text(".train-status")
    finally:
        console.close()

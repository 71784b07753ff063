"""The Live page in a real browser, on the real live engine: two streams replayed from
the LASER set run through recognition with the shipped gesture model; each tile's
skeleton and raw-gesture label follow the engine's events."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from ui_helpers import laser_clip, login, screenshot, start_console, wait_for

PIXEL_HASH = """c => {
  const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
  let h = 0;
  for (let i = 0; i < d.length; i += 4) h = (h * 31 + d[i] + 3 * d[i + 1] + 7 * d[i + 2]) | 0;
  return [Number(c.dataset.poseCount), h];
}"""


@pytest.fixture(scope="module")
def checkpoint() -> Path:
    from proxima.gesture.classifier import default_checkpoint

    path = Path(os.environ.get("PROXIMA_TEST_CHECKPOINT") or default_checkpoint())
    assert path.is_file(), f"the live tile test needs the gesture checkpoint at {path}"
    return path


def test_tiles_follow_the_engine(page, tmp_path: Path, checkpoint: Path) -> None:  # type: ignore[no-untyped-def]
    console = start_console(
        tmp_path,
        with_engine=True,
        streams=[
            {"name": "front", "uri": f"replay:{laser_clip('move_to_left_f')}@30", "drone": "main"},
            {
                "name": "left",
                "uri": f"replay:{laser_clip('move_to_left_l')}@30",
                "drone": "second",
                "priority": 1,
            },
        ],
        drones=[
            {"name": "main", "connection": "udpin:127.0.0.1:14550"},
            {"name": "second", "connection": "udpin:127.0.0.1:14560", "sysid": 2},
        ],
        engine={"checkpoint": str(checkpoint)},
    )
    assert console.runtime.engine is not None, console.runtime.notes
    gestures = console.bus.subscribe(types=["gesture"])
    latest: dict[str, str] = {}

    def newest(stream: str) -> str | None:
        for e in gestures.drain():
            latest[e.stream] = e.gesture
        return latest.get(stream)

    try:
        login(page, console.url)
        tile = "article.tile[data-stream=front]"
        page.wait_for_selector(f"{tile} canvas[data-pose-count]")

        def skeleton() -> tuple[int, int]:
            """The tile's pose count and a hash of its canvas pixels."""
            return page.eval_on_selector(f"{tile} canvas", PIXEL_HASH)

        count0, pixels0 = wait_for(lambda: (s := skeleton())[0] > 5 and s, what="poses")
        page.wait_for_timeout(700)
        count1, pixels1 = skeleton()
        assert count1 > count0 + 10, "the skeleton stopped updating"
        assert pixels1 != pixels0, "the canvas did not redraw"

        # The raw gesture label shows the engine's newest classification of that stream.
        def label() -> str:
            return page.inner_text(f"{tile} .value.gesture")

        wait_for(lambda: label() != "—", timeout=20, what="a gesture label")
        shown = wait_for(
            lambda: (g := newest("front")) is not None and label().split(" ")[0] == g and g,
            timeout=10,
            what="the label to match the engine's newest gesture",
        )
        assert shown in console.runtime.engine.pipelines["front"].classifier.labels
        texts = {label()}
        wait_for(
            lambda: texts.add(label()) or len(texts) > 1,
            timeout=15,
            what="the label to change with new classifications",
        )
        assert page.inner_text(f"{tile} .value.state") == "live"
        # Which drone is commanded, and why (issue 26, finding 6): front drives (the
        # main camera sees the operator), left is standby; the badges explain
        # themselves; gesture control was never armed (no have_command in these
        # clips), so the summary says no drone is driving.
        page.wait_for_selector(f"{tile} .driving-badge")
        assert "command main now" in page.get_attribute(f"{tile} .driving-badge", "title")
        assert "operator" in page.get_attribute(f"{tile} .driving-badge", "title")
        assert "the main camera" in page.get_attribute(f"{tile} .b-priority", "title")
        side = "article.tile[data-stream=left]"
        page.wait_for_selector(f"{side} .standby-badge")
        assert "if front loses the operator" in page.get_attribute(
            f"{side} .standby-badge", "title"
        )
        assert "priority 1" in page.get_attribute(f"{side} .b-priority", "title")
        who = page.inner_text(".who-drives")
        assert who.startswith("No drone driving: gesture control disarmed"), who
        assert "front would drive main" in who and "left is standby, priority 1" in who
        screenshot(page, "live")
    finally:
        gestures.close()
        console.close()


def test_a_thumb_gesture_the_camera_cannot_confirm_is_marked_withheld(  # type: ignore[no-untyped-def]
    page, tmp_path: Path, checkpoint: Path
) -> None:
    # The left camera sees the operator's left side: the right hand, whose thumb tells
    # all_clear from not_clear, is behind the body.
    console = start_console(
        tmp_path,
        with_engine=True,
        streams=[
            {"name": "left", "uri": f"replay:{laser_clip('all_clear_l')}@30", "drone": "main"}
        ],
        drones=[{"name": "main", "connection": "udpin:127.0.0.1:14550"}],
        engine={"checkpoint": str(checkpoint)},
    )
    assert console.runtime.engine is not None, console.runtime.notes
    try:
        login(page, console.url)
        field = "article.tile[data-stream=left] .value.gesture"
        page.wait_for_selector(field)
        text = wait_for(
            lambda: "hand not seen: withheld" in (t := page.inner_text(field)) and t,
            timeout=30,
            what="the withheld mark",
        )
        assert text.split(" ")[0] in ("all_clear", "not_clear")
        assert "withheld" in page.get_attribute(field, "class")
    finally:
        console.close()

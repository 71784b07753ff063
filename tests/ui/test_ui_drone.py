"""The console with a real simulated vehicle (`proxima sim-drone`, MAVLink over UDP on
127.0.0.1) flown through the project's link: the 3D view shows it with its trail, and
the emergency stop asks for confirmation before it lands the drone."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from ui_helpers import Console, laser_clip, login, screenshot, start_console, wait_for

from proxima.api.feed import ReplayPoseFeed
from proxima.events import CommandEvent, HandoverEvent

PROXIMA = str(Path(sys.executable).with_name("proxima"))


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def flying(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Console]:
    """A console linked to one simulated drone that took off to 3 m and flew 4 m east,
    with the operator's pose replayed from the LASER set."""
    port = _free_udp_port()
    sim = subprocess.Popen(
        [
            PROXIMA,
            "sim-drone",
            "--port",
            str(port),
            "--max-accel",
            "8",
            "--max-climb",
            "4",
            "--land-speed",
            "3",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    uri = f"replay:{laser_clip('move_to_right_f')}@30"
    console = feed = None
    try:
        console = start_console(
            tmp_path_factory.mktemp("drone"),
            with_drones=True,
            with_view=True,
            streams=[{"name": "front", "uri": uri, "drone": "main"}],
            drones=[
                {"name": "main", "connection": f"udpin:127.0.0.1:{port}", "home": (0.0, -6.0, 0.0)}
            ],
        )
        feed = ReplayPoseFeed(console.bus, {"front": uri}).start()
        console.bus.publish(
            HandoverEvent(t=0.0, stream="front", from_stream="", to_stream="front", reason="start")
        )
        link = console.runtime.links["main"]
        assert link.enter_guided().ok and link.arm().ok and link.takeoff(3.0).ok
        wait_for(
            lambda: (t := link.telemetry()) and t.altitude and t.altitude > 2.5,
            timeout=20,
            what="take-off",
        )
        assert link.goto_local(0.0, 4.0, -3.0).ok
        wait_for(lambda: link.telemetry().position[1] > 3.8, timeout=20, what="the move east")
        yield console
    finally:
        if feed is not None:
            feed.stop()
        if console is not None:
            console.close()
        sim.terminate()
        try:
            sim.wait(10)
        except subprocess.TimeoutExpired:
            sim.kill()
            sim.wait()


def _emergency_rows(console: Console) -> list[dict]:
    from proxima.store.command_log import CommandLog

    rows = CommandLog(console.runtime.app.state.console.db_engine).recent(limit=50)
    return [r for r in rows if r["command"] == "emergency_stop"]


def test_3d_view_shows_the_drone(page, flying: Console) -> None:  # type: ignore[no-untyped-def]
    view = flying.runtime.view
    assert view is not None and view.host == "127.0.0.1"
    trail = wait_for(
        lambda: len(view.model.snapshot()["drones"]["main"]["trail"]) > 10,
        what="a trail in the 3D model",
    )
    assert trail
    login(page, flying.url)
    page.click("nav a[data-page='3d']")
    # Through the console's own port, behind its login: viser's port is never shown.
    assert page.get_attribute("iframe.viser", "src") == "/viser/"
    frame = page.frame_locator("iframe.viser")
    frame.locator("text=Connected").wait_for()
    # viser's own control panel starts minimised to its status bar: no scene tree.
    page.wait_for_timeout(1000)
    assert not frame.locator("text=/drones").is_visible()
    page.wait_for_timeout(1500)  # let WebGL draw the scene
    screenshot(page, "3d-view")


def test_telemetry_is_legible(page, flying: Console) -> None:  # type: ignore[no-untyped-def]
    """Finding 7: altitude above home (positive up, where the link's NED says -3),
    heading, ground speed, how long ago the vehicle was heard, and the current target."""
    import re

    login(page, flying.url)
    card = ".drone[data-drone=main]"
    page.wait_for_selector(f"{card} .telemetry:has-text('above home')")
    text = page.inner_text(f"{card} .telemetry")
    alt = float(re.search(r"alt (-?[\d.]+) m above home", text).group(1))
    assert 2.5 < alt < 3.5, text  # up is positive
    assert re.search(r"heading \d+°", text) and re.search(r"speed [\d.]+ m/s", text), text
    age = float(re.search(r"heard ([\d.]+) s ago", text).group(1))
    assert age < 3.0, text
    target = page.inner_text(f"{card} .target")
    assert re.search(r"target -?0\.0 m N, 4\.0 m E, alt 3\.0 m", target), target


def test_emergency_stop_asks_for_confirmation(page, flying: Console) -> None:  # type: ignore[no-untyped-def]
    link = flying.runtime.links["main"]
    login(page, flying.url)
    page.wait_for_selector(".drone[data-drone=main] .badge.l-ok")

    page.click("#estop-open")
    page.wait_for_selector("#estop-dialog[open]")
    page.click("#estop-request")
    page.wait_for_selector("#estop-step2:not([hidden])")
    assert "Really stop main?" in page.inner_text("#estop-question")
    screenshot(page, "emergency-stop-confirm")
    time.sleep(1.0)
    # Asking changed nothing: still flying; the log holds only the request, not sent.
    assert link.telemetry().landed == "in_air" and link.telemetry().altitude > 2.5
    rows = _emergency_rows(flying)
    assert [(r["status"], r["sent"]) for r in rows] == [("pending", None)]
    page.click("#estop-step2 .cancel")
    assert not page.is_visible("#estop-dialog")
    time.sleep(0.5)
    assert link.telemetry().landed == "in_air"

    page.click("#estop-open")
    page.click("#estop-request-all")  # every configured drone: here the one
    assert "Really stop main?" in page.inner_text("#estop-question")
    page.click("#estop-confirm")
    # The dialog reports and closes; the banner keeps the result (issue 26, finding 5).
    page.wait_for_selector("#estop-dialog", state="hidden")
    page.wait_for_selector("#banner.ok:has-text('main: emergency stop sent')")
    sent = wait_for(
        lambda: [r for r in _emergency_rows(flying) if r["status"] == "sent"],
        what="the logged emergency stop",
    )
    assert sent[0]["drone"] == "main" and sent[0]["sent"] is not None
    wait_for(lambda: link.telemetry().altitude < 0.3, timeout=20, what="the landing")

    # Never stale (finding 2): the tile and the card say stopped, not armed or driving.
    page.wait_for_selector(".tile[data-stream=front].stopped .badge.stopped-badge")
    assert "STOPPED" in page.inner_text(".tile[data-stream=front] .value.armed")
    assert not page.query_selector(".tile[data-stream=front] .driving-badge")
    page.wait_for_selector(".drone[data-drone=main] .badge.stopped-badge")
    screenshot(page, "emergency-stop-stopped")
    link_state = flying.runtime.drones.gesture_control_armed("main")
    assert link_state is False
    # Resume behind a confirmation: the stop clears, gesture control stays off until
    # the operator's have_command.
    page.once("dialog", lambda d: d.accept())
    page.click(".drone[data-drone=main] button.resume")
    page.wait_for_selector("#banner.ok:has-text('resumed')")
    page.wait_for_selector(".tile[data-stream=front]:not(.stopped)")
    assert not link.emergency_stopped
    assert "disarmed" in page.inner_text(".tile[data-stream=front] .value.armed")


def test_command_log_rows_reasons_reload_filter_and_csv(page, flying: Console) -> None:  # type: ignore[no-untyped-def]
    """Finding 3: one row per command with its life cycle, the refusal's reason in the
    row, the same rows (times, outcomes, emergency stops) after logging in again, a
    filter by drone and outcome, and CSV export."""
    login(page, flying.url)
    page.wait_for_selector(".drone[data-drone=main] .badge.l-ok")
    # This test needs the drone the test before landed (a module's tests run in order on
    # one worker); a move is refused "not flying" only once the drone reads on the ground.
    link = flying.runtime.links["main"]
    wait_for(lambda: link.telemetry().landed == "on_ground", timeout=30, what="on the ground")
    t0 = time.time()
    for i, command in enumerate(("move_upward", "have_command", "move_upward")):
        flying.bus.publish(CommandEvent(t=t0 + i, stream="front", command=command, drone="main"))
        time.sleep(0.3)
    log = ".command-log tbody"
    # Disarmed: refused with the reason; then armed; then refused (on the ground).
    page.wait_for_selector(f"{log} tr.g-refused .reason:has-text('not armed')")
    page.wait_for_selector(f"{log} tr .stage:has-text('control armed')")
    page.wait_for_selector(f"{log} tr.g-refused .reason:has-text('not flying')")
    rows = page.query_selector_all(f"{log} tr")
    cmds = [c.inner_text() for c in page.query_selector_all(f"{log} .cmd")]
    # One row per command, not one per event.
    assert cmds.count("move_upward") == 2 and cmds.count("have_command") == 1, cmds
    stops = [r.inner_text() for r in rows if "emergency_stop" in r.inner_text()]
    assert any("sent" in s for s in stops), stops
    screenshot(page, "command-log")

    # Log out and in: the same rows, with times and outcomes, emergency stops included.
    page.click("#logout")
    page.wait_for_selector("#login-form:not([hidden])")
    login(page, flying.url)
    page.wait_for_selector(f"{log} tr.g-refused .reason:has-text('not flying')")
    rows = [r.inner_text() for r in page.query_selector_all(f"{log} tr")]
    cmds = [c.inner_text() for c in page.query_selector_all(f"{log} .cmd")]
    assert cmds.count("move_upward") == 2 and cmds.count("have_command") == 1, rows
    assert any("emergency_stop" in r and "sent" in r for r in rows), rows
    assert all("—" not in r.split("\t")[0] for r in rows), rows  # every row has its time
    assert not any(r.rstrip().endswith("decided") for r in rows if "move_upward" in r)

    page.select_option("select.log-outcome", "refused")
    page.wait_for_function(
        "() => [...document.querySelectorAll('.command-log tbody tr')]"
        ".every(r => r.classList.contains('g-refused'))"
    )
    assert len(page.query_selector_all(f"{log} tr.g-refused")) >= 2
    page.select_option("select.log-outcome", "")
    page.select_option("select.log-drone", "main")
    with page.expect_download() as download:
        page.click("button.export-csv")
    text = Path(download.value.path()).read_text()
    header, *lines = text.strip().splitlines()
    assert header.startswith("id,created_at,drone,source,command")
    assert any("emergency_stop" in line for line in lines)
    assert any("move_upward" in line and "refused" in line for line in lines)

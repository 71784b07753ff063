"""Alarms in the browser (issue 26, finding 4): a simulated drone (the project's
MAVLink simulator on a thread, real UDP) taking off on a nearly empty battery drains
it: the console raises a battery warning, then a critical alarm, and when the
autopilot's battery failsafe lands it, a critical "on its own" alarm; the banner shows
it on every page and the Live page's alarm log lists each."""

from __future__ import annotations

import socket
import threading
from pathlib import Path

from ui_helpers import login, screenshot, start_console, wait_for

from proxima.drone.sim import SimConfig, VehicleServer


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_battery_and_failsafe_alarms_are_visible(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    port = _free_udp_port()
    # 22 %: just above what the simulator refuses to arm with; 20 s of flight per 100 %.
    cfg = SimConfig(port=port, battery_pct=22.0, battery_flight_s=20.0,
                    max_accel=8.0, max_climb=4.0, land_speed=3.0)  # fmt: skip
    server, stop = VehicleServer(cfg), threading.Event()
    thread = threading.Thread(target=server.run, args=(stop,), daemon=True)
    thread.start()
    console = None
    try:
        console = start_console(
            tmp_path,
            with_drones=True,
            drones=[{"name": "main", "connection": f"udpin:127.0.0.1:{port}"}],
            server={"db_path": str(tmp_path / "c.db"), "viser_enabled": False},
        )
        link = console.runtime.links["main"]
        login(page, console.url)
        page.wait_for_selector(".drone[data-drone=main] .badge.l-ok")
        assert page.is_hidden("#alarm-banner")
        assert link.enter_guided().ok and link.arm().ok and link.takeoff(3.0).ok
        page.wait_for_selector("#alarm-banner.sev-warning:has-text('battery')")
        page.wait_for_selector(".drone[data-drone=main] .battery.sev-warning")
        page.wait_for_selector("#alarm-banner.sev-critical")
        page.wait_for_selector(
            ".alarms .alarm.sev-critical[data-kind=failsafe_landing]", timeout=20000
        )
        assert "on its own" in page.inner_text(".alarms")
        page.click(".alarm-history summary")
        log = page.inner_text(".alarm-log")
        assert "warning: main: battery" in log and "critical: main: battery" in log
        screenshot(page, "alarms")
        # The banner stays on other pages.
        page.click("nav a[data-page=training]")
        assert page.is_visible("#alarm-banner.sev-critical")
        wait_for(lambda: link.telemetry().landed == "on_ground", timeout=20, what="the landing")
        audit = console.runtime.app.state.console.audit.store.query(action="alarm")
        assert {r.detail["kind"] for r in audit} == {"battery_low", "failsafe_landing"}
    finally:
        if console is not None:
            console.close()
        stop.set()
        thread.join(timeout=5.0)

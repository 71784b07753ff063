"""MAVProxy (PyPI `MAVProxy` 1.8.x, ArduPilot's ground station), driven through its
console on stdin, flies `proxima sim-drone` (ArduPilot mode): parameters fetched, shown
and set, version, waypoint, fence and rally lists, mode, arm, takeoff, `guided LAT LON
ALT`, a mission with a landing sequence uploaded with `wp load`, and `land`.

MAVProxy wants opencv-python, vtk, shapely and matplotlib, so it gets a virtualenv of
its own, made once and kept under runs/test-cache/ (the first one took 40 s to 150 s
here, with the machine busy; pip's own cache makes a remake quicker). The test is
skipped, saying why, only when pip cannot install MAVProxy.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from conftest import StartSim

MAVPROXY = "MAVProxy==1.8.75"
ROOT = Path(__file__).resolve().parents[2]
VENV = (
    ROOT
    / "runs"
    / "test-cache"
    / f"mavproxy-{MAVPROXY.split('==')[1]}-py{sys.version_info[0]}{sys.version_info[1]}"
)
HOME_LAT, HOME_LON = 50.0755, 14.4378

pytestmark = pytest.mark.timeout(600)


def mavproxy_venv() -> Path:
    """The virtualenv with MAVProxy (made on first use); its mavproxy.py.

    Skips the test when pip cannot install MAVProxy."""
    script = VENV / "bin" / "mavproxy.py"
    done = VENV / ".installed"
    if done.exists() and script.exists():
        return script
    t0 = time.monotonic()
    subprocess.run([sys.executable, "-m", "venv", "--clear", str(VENV)], check=True)
    pip = [str(VENV / "bin" / "python"), "-m", "pip", "install", "--disable-pip-version-check"]
    out = subprocess.run([*pip, MAVPROXY], capture_output=True, text=True, timeout=900)
    if out.returncode != 0:
        pytest.skip(f"pip could not install {MAVPROXY}: {out.stderr.strip()[-400:]}")
    done.write_text(f"made in {time.monotonic() - t0:.0f} s\n")
    return script


class Console:
    """MAVProxy's console: commands go to its stdin, its output is read on a thread."""

    def __init__(self, script: Path, port: int, cwd: Path) -> None:
        env = {**os.environ, "HOME": str(cwd)}  # no ~/.mavinit.scr of the user's
        self.proc = subprocess.Popen(
            [str(script), f"--master=udpin:127.0.0.1:{port}", "--no-state"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            cwd=cwd,
            env=env,
        )
        self.out = ""
        self.mark = 0
        self._lock = threading.Lock()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        while chunk := os.read(self.proc.stdout.fileno(), 4096):
            with self._lock:
                self.out += chunk.decode(errors="replace")

    def send(self, line: str) -> None:
        assert self.proc.stdin is not None
        with self._lock:
            self.mark = len(self.out)  # expect() looks at what came after this command
        self.proc.stdin.write((line + "\n").encode())
        self.proc.stdin.flush()

    def expect(self, pattern: str, timeout: float = 10.0) -> re.Match[str]:
        """The first match of `pattern` in the output since the last command.

        Raises:
            AssertionError: no match within `timeout` seconds (with the output's tail).
        """
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self._lock:
                found = re.search(pattern, self.out[self.mark :])
            if found:
                return found
            time.sleep(0.05)
        raise AssertionError(f"no {pattern!r} from MAVProxy in {timeout} s:\n{self.out[-3000:]}")

    def ask(self, line: str, pattern: str, timeout: float = 10.0) -> re.Match[str]:
        self.send(line)
        return self.expect(pattern, timeout)

    def poll(self, line: str, pattern: str, ok: Callable[[float], bool], timeout: float) -> None:
        """Repeat `line` until the number its output's `pattern` captures is `ok`."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            found = self.ask(line, pattern, 3.0)
            if ok(float(found.group(1))):
                return
            time.sleep(0.3)
        raise AssertionError(f"{line!r}: {pattern!r} never satisfied:\n{self.out[-2000:]}")

    def close(self) -> int:
        assert self.proc.stdin is not None
        self.proc.stdin.close()  # end of input: MAVProxy unloads its modules and exits
        try:
            return self.proc.wait(15)
        except subprocess.TimeoutExpired:
            self.proc.kill()  # by its own handle, only this process
            return self.proc.wait()


LANDING = f"""QGC WPL 110
0\t1\t0\t16\t0\t0\t0\t0\t{HOME_LAT}\t{HOME_LON}\t300\t1
1\t0\t3\t189\t0\t0\t0\t0\t0\t0\t0\t1
2\t0\t3\t21\t0\t0\t0\t0\t{HOME_LAT + 4 / 111_320:.7f}\t{HOME_LON}\t0\t1
"""


def test_mavproxy_flies_the_simulator(start_sim: StartSim, tmp_path: Path) -> None:
    script = mavproxy_venv()
    sim = start_sim()
    (tmp_path / "landing.txt").write_text(LANDING)
    mp = Console(script, sim.port, tmp_path)
    try:
        mp.expect(r"online system 1", 30.0)
        # At start MAVProxy fetches the parameters: FTP first (refused at once), then
        # PARAM_REQUEST_LIST.
        mp.expect(r"Received 23 parameters", 30.0)
        mp.ask("param fetch", r"Received 23 parameters")
        mp.ask("param show WPNAV_SPEED", r"WPNAV_SPEED\s+500")
        mp.send("param set WPNAV_SPEED 400")
        time.sleep(0.5)
        mp.ask("param show WPNAV_SPEED", r"WPNAV_SPEED\s+400")
        mp.send("version")
        time.sleep(0.5)
        version = mp.ask("status AUTOPILOT_VERSION", r"flight_sw_version : (\d+)")
        assert int(version.group(1)) >> 16 == 0x0405  # 4.5
        mp.ask("wp list", r"Requesting 1 waypoints")  # ArduPilot's home
        mp.ask("fence list", r"Requesting 0 fence items")
        mp.ask("rally list", r"Requesting 0 rally items")

        mp.ask("mode guided", r"DO_SET_MODE: ACCEPTED")
        mp.ask("arm throttle", r"COMPONENT_ARM_DISARM: ACCEPTED")
        mp.ask("takeoff 3", r"NAV_TAKEOFF: ACCEPTED")
        mp.poll(
            "status GLOBAL_POSITION_INT",
            r"relative_alt : (-?\d+)",
            lambda a: abs(a - 3000) < 150,
            15.0,
        )
        north = HOME_LAT + 6 / 111_320
        mp.ask(f"guided {north:.7f} {HOME_LON} 4", r"DO_REPOSITION: ACCEPTED")
        lat_e7 = round(north * 1e7)
        mp.poll(
            "status GLOBAL_POSITION_INT", r"lat : (-?\d+)", lambda x: abs(x - lat_e7) < 10, 15.0
        )

        mp.ask("wp load landing.txt", r"MISSION_ACK: TYPE_MISSION: ACCEPTED")
        mp.ask("wp list", r"Requesting 3 waypoints")
        mp.ask("land", r"DO_LAND_START: ACCEPTED")
        mp.expect(r"DISARMED", 30.0)
        landed = mp.ask("status GLOBAL_POSITION_INT", r"lat : (-?\d+)")
        assert abs(int(landed.group(1)) - round((HOME_LAT + 4 / 111_320) * 1e7)) < 15
    finally:
        code = mp.close()
    assert sim.proc.poll() is None, "the simulator died"
    assert code >= 0, mp.out[-2000:]  # it ended by itself (1: MAVProxy's exit on end of input)

"""A watchdog that ends a deployment's Flower processes when the process that started
them ends, however it ends (SIGTERM, SIGINT, SIGHUP, SIGKILL, a crash).

The Flower processes run in their own process groups, so signals meant for the console
(a terminal's Ctrl-C, a service manager's SIGTERM) do not reach them, and the console's
own clean-up cannot run when it is killed outright. `Reaper` starts this file as a small
stdlib-only process (`python -I reaper.py`) in a session of its own and keeps the write
end of a pipe to its stdin; it registers each process group it starts (`+PGID`) and
unregisters it once it has ended it itself (`-PGID`). When the pipe closes (the parent
is gone or closed it) or the watchdog gets SIGTERM, every group still registered gets
SIGTERM, and SIGKILL after a grace period. The watchdog ignores SIGINT and SIGHUP so a
Ctrl-C or a closed terminal cannot take it down before the groups it guards.

Flower's own children of those processes (the SuperLink's SuperExec and the ServerApp,
a SuperNode's ClientApp processes) watch their parent's PID and exit when it is gone.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

GRACE_S = 3.0


class Reaper:
    """The parent's side: start the watchdog, register and unregister process groups."""

    def __init__(self) -> None:
        self._proc: subprocess.Popen[bytes] | None = None
        self._groups: set[int] = set()
        self._lock = threading.Lock()

    def _start(self) -> subprocess.Popen[bytes]:
        proc = subprocess.Popen(
            [sys.executable, "-I", str(Path(__file__).resolve())],
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            start_new_session=True,  # no terminal signal reaches it
        )
        assert proc.stdin is not None
        for pgid in self._groups:  # a replacement guards what its predecessor did
            proc.stdin.write(f"+{pgid}\n".encode())
        return proc

    def _send(self, line: str) -> None:
        with self._lock:
            for _ in range(2):
                if self._proc is None or self._proc.poll() is not None:
                    self._proc = self._start()
                assert self._proc.stdin is not None
                try:
                    self._proc.stdin.write(line.encode() + b"\n")
                    self._proc.stdin.flush()
                    return
                except BrokenPipeError:  # it died: the next pass starts another
                    self._proc = None

    def watch(self, pgid: int) -> None:
        """End process group `pgid` when this process ends."""
        self._groups.add(pgid)
        self._send(f"+{pgid}")

    def release(self, pgid: int) -> None:
        """Forget `pgid` (its processes were ended and waited for)."""
        if pgid in self._groups:
            self._groups.discard(pgid)
            self._send(f"-{pgid}")

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc is not None else None

    def close(self, timeout: float = GRACE_S + 2.0) -> None:
        """Close the pipe: the watchdog ends what is still registered, then exits."""
        with self._lock:
            proc, self._proc = self._proc, None
            self._groups.clear()
        if proc is None:
            return
        if proc.stdin is not None:
            with contextlib.suppress(BrokenPipeError):
                proc.stdin.close()
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)


def _end(groups: set[int], grace: float) -> None:
    """SIGTERM every group, then SIGKILL what is left of them after `grace` seconds."""
    for pgid in groups:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pgid, signal.SIGTERM)
    deadline = time.monotonic() + grace
    alive = set(groups)
    while alive and time.monotonic() < deadline:
        time.sleep(0.1)
        for pgid in list(alive):
            try:
                os.killpg(pgid, 0)
            except (ProcessLookupError, PermissionError):
                alive.discard(pgid)
    for pgid in alive:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pgid, signal.SIGKILL)


def main() -> None:
    """The watchdog: read `+PGID` / `-PGID` lines until EOF or SIGTERM, then end the
    groups still registered."""
    groups: set[int] = set()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)

    def on_term(_sig: int, _frame: object) -> None:
        _end(groups, GRACE_S)
        os._exit(0)

    signal.signal(signal.SIGTERM, on_term)
    for raw in sys.stdin.buffer:
        line = raw.strip().decode(errors="replace")
        if len(line) < 2 or line[0] not in "+-" or not line[1:].isdigit() or int(line[1:]) < 2:
            continue  # never group 0 (our own) or 1
        if line[0] == "+":
            groups.add(int(line[1:]))
        else:
            groups.discard(int(line[1:]))
    _end(groups, GRACE_S)


if __name__ == "__main__":
    main()

"""Ending a deployment's Flower processes, all of them, however the console ends.

Two problems, one module:

- **Trees that leave their group.** The SuperLink starts its SuperExec in a session of
  its own, and the SuperExec the ServerApp in that session; Flower ends those when their
  parent's PID disappears, but a PID lingers as a zombie where nothing reaps orphans
  (a container whose first process does not, a subreaper), and a ServerApp waiting on a
  dead SuperLink then retries for ever. So the process tree is read from /proc (Linux;
  elsewhere only process groups are ended) and every descendant is ended by PID, each
  checked by its start time so that a reused PID is never hit.
- **A console killed outright.** Signals meant for the console (a terminal's Ctrl-C, a
  service manager's SIGTERM, a closed terminal's SIGHUP) do not reach Flower processes
  in their own process groups, and a console killed by SIGTERM's default action or
  SIGKILL runs no clean-up. `Reaper` starts this file as a small stdlib-only watchdog
  (`python -I reaper.py`, its own session) holding the read end of a pipe: the parent
  registers each process group it starts (`+PGID`) and unregisters those it ended itself
  (`-PGID`). Every second the watchdog notes the descendants of what is registered; when
  the pipe closes (the parent is gone or closed it) or it gets SIGTERM, it ends them all
  (SIGTERM, SIGKILL after a grace period). It ignores SIGINT and SIGHUP, so a Ctrl-C or
  a closed terminal cannot take it down before what it guards.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

GRACE_S = 3.0
SCAN_S = 1.0


# /proc ---------------------------------------------------------------------------------


def _stat(pid: int) -> tuple[str, int, int, int] | None:
    """(state, parent pid, process group, start time) of a process; None if gone."""
    try:
        raw = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    f = raw[raw.rindex(")") + 2 :].split()
    return f[0], int(f[1]), int(f[2]), int(f[19])


def descendants(roots: set[int]) -> dict[int, int]:
    """Every living process in the trees under `roots` (PIDs) or in their process groups,
    roots included: PID -> start time. Empty where there is no /proc."""
    if not Path("/proc/self/stat").exists():
        return {}
    table: dict[int, tuple[str, int, int, int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (st := _stat(int(entry))) is not None:
            table[int(entry)] = st
    children: dict[int, list[int]] = {}
    for pid, (_, ppid, _, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    todo = [p for p, st in table.items() if p in roots or st[2] in roots]
    out: dict[int, int] = {}
    while todo:
        pid = todo.pop()
        if pid in out or pid not in table:
            continue
        if table[pid][0] != "Z":
            out[pid] = table[pid][3]
        todo.extend(children.get(pid, []))
    return out


def _alive(pid: int, start: int) -> bool:
    st = _stat(pid)
    return st is not None and st[3] == start and st[0] != "Z"


def _signal(procs: dict[int, int], groups: set[int], sig: int) -> None:
    for pgid in groups:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pgid, sig)
    for pid, start in procs.items():
        if _alive(pid, start):  # the same process, not a reused PID
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, sig)


def end_all(groups: set[int], procs: dict[int, int], grace: float = GRACE_S) -> None:
    """SIGTERM the process groups and the processes (PID -> start time, as from
    `descendants`, which lists the groups' members too); once those processes are gone,
    or after `grace` seconds, SIGKILL whatever is left in the groups and of the processes
    (what started meanwhile included)."""
    _signal(procs, groups, signal.SIGTERM)
    deadline = time.monotonic() + grace
    while time.monotonic() < deadline and any(_alive(p, s) for p, s in procs.items()):
        time.sleep(0.1)
    _signal(procs, groups, signal.SIGKILL)


# the parent's side -----------------------------------------------------------------------


class Reaper:
    """Start the watchdog and tell it which process groups to guard."""

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
        """End process group `pgid` and its processes' descendants when this process ends."""
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


# the watchdog ----------------------------------------------------------------------------


def _parse(line: str, groups: set[int]) -> None:
    if len(line) < 2 or line[0] not in "+-" or not line[1:].isdigit() or int(line[1:]) < 2:
        return  # never group 0 (our own) or 1
    if line[0] == "+":
        groups.add(int(line[1:]))
    else:
        groups.discard(int(line[1:]))


def main() -> None:
    """Read `+PGID` / `-PGID` lines, note the registered groups' descendants every
    second, and end them all at EOF or on SIGTERM."""
    groups: set[int] = set()
    seen: dict[int, int] = {}  # every descendant noted while its group was registered
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)

    def finish(*_: object) -> None:
        seen.update(descendants(groups))
        end_all(groups, seen)
        os._exit(0)

    signal.signal(signal.SIGTERM, finish)
    buf = b""
    while True:
        ready, _, _ = select.select([0], [], [], SCAN_S)
        if ready:
            chunk = os.read(0, 4096)
            if not chunk:
                finish()
            buf += chunk
            *lines, buf = buf.split(b"\n")
            for raw in lines:
                _parse(raw.strip().decode(errors="replace"), groups)
        seen.update(descendants(groups))
        seen = {p: s for p, s in seen.items() if _alive(p, s)}


if __name__ == "__main__":
    main()

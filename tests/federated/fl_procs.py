"""Process-tree helpers for the hygiene tests (Linux /proc).

Flower starts some of its processes in sessions of their own (the SuperLink's
SuperExec), so "no child remains" is checked with this test process made a child
subreaper: every orphan of the tree is re-parented to it, and a process that outlived
its parent still shows up among this process's descendants.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import time
from collections.abc import Iterator
from pathlib import Path

PR_SET_CHILD_SUBREAPER = 36


def _stat(pid: int) -> tuple[str, int] | None:
    """(state, parent pid) of a process, None if it is gone."""
    try:
        raw = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = raw[raw.rindex(")") + 2 :].split()
    return fields[0], int(fields[1])


def cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode().strip()
    except OSError:
        return ""


def descendants(root: int) -> dict[int, str]:
    """Living (not zombie) descendants of `root`: pid -> command line."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (st := _stat(int(entry))) is not None and st[0] != "Z":
            children.setdefault(st[1], []).append(int(entry))
    out: dict[int, str] = {}
    todo = list(children.get(root, []))
    while todo:
        pid = todo.pop()
        out[pid] = cmdline(pid)
        todo.extend(children.get(pid, []))
    return out


def wait_gone(root: int, timeout: float, ignore: set[int] | None = None) -> dict[int, str]:
    """Poll until `root` has no living descendants besides `ignore` (or `timeout`);
    returns what is left."""
    deadline = time.monotonic() + timeout
    while True:
        left = {p: c for p, c in descendants(root).items() if p not in (ignore or set())}
        if not left or time.monotonic() >= deadline:
            return left
        time.sleep(0.2)


@contextlib.contextmanager
def subreaper() -> Iterator[None]:
    """Make this process a child subreaper for the duration (Linux only)."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_CHILD_SUBREAPER) failed")
    try:
        yield
    finally:
        libc.prctl(PR_SET_CHILD_SUBREAPER, 0, 0, 0, 0)

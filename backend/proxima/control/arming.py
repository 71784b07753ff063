"""Arming of gesture control: no motion command reaches a drone until the operator
performed `have_command`.

Armed control disarms after `idle_disarm_s` stream seconds without a command, on
`wave_off` (after sending it: wave-off means abort and hover), and when the caller says so
(a handover, the operator lost everywhere).
"""

from __future__ import annotations

ARM_GESTURE = "have_command"
ABORT_GESTURE = "wave_off"


class Arming:
    """The armed / disarmed state of one controlled drone's gesture control."""

    def __init__(self, idle_disarm_s: float = 60.0) -> None:
        self.idle_disarm_s = idle_disarm_s
        self.armed = False
        self._last_activity: float | None = None

    def allows(self, command: str) -> bool:
        """Whether `command` may be sent now: anything when armed, only the arming gesture
        when disarmed."""
        return self.armed or command == ARM_GESTURE

    def on_command(self, t: float, command: str) -> tuple[bool, str] | None:
        """Account for a command sent at `t`; return (armed, reason) if the state changed."""
        self._last_activity = t
        if command == ARM_GESTURE and not self.armed:
            self.armed = True
            return True, ARM_GESTURE
        if command == ABORT_GESTURE and self.armed:
            self.armed = False
            return False, ABORT_GESTURE
        return None

    def check_idle(self, t: float) -> bool:
        """Disarm if armed and idle for `idle_disarm_s`; return whether it disarmed."""
        last = self._last_activity
        if self.armed and last is not None and t - last >= self.idle_disarm_s:
            self.armed = False
            return True
        return False

    def disarm(self) -> bool:
        """Disarm now; return whether it was armed."""
        was = self.armed
        self.armed = False
        return was

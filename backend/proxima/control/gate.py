"""Debounce between commands: when a filtered action becomes a command.

A command fires on the rising edge of an action: the filter names a new action, it has
held for `confirm` decisions (or its own count in `confirm_by_command`: a wrong `land`
costs more than a late one), and at least `debounce_s` passed since the previous command.
Holding a gesture sends its command once (or every `repeat_s` if set); the same command
fires again only after the action was gone for `release_s`. A command held back by the
debounce is not lost: it fires as soon as the wait ends if the action is still there.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping


class CommandGate:
    """Turns a stream of filtered actions into commands (all times in stream seconds)."""

    def __init__(
        self,
        debounce_s: float = 2.0,
        confirm: int = 1,
        release_s: float = 2.0,
        repeat_s: float | None = None,
        confirm_by_command: Mapping[str, int] | None = None,
    ) -> None:
        self.confirm_by_command = dict(confirm_by_command or {})
        for name, n in {"confirm": confirm, **self.confirm_by_command}.items():
            if n < 1:
                raise ValueError(f"{name} must be >= 1, got {n}")
        self.debounce_s = debounce_s
        self.confirm = confirm
        self.release_s = release_s
        self.repeat_s = repeat_s
        self.latched: str | None = None  # the last command, while its action is held
        self.last_fire_t: float | None = None
        self._gone_since: float | None = None  # when the latched action stopped
        self._previous = ""
        self._streak = 0

    def restart_streak(self) -> None:
        """Forget the agreement count, e.g. when another stream starts driving."""
        self._previous = ""
        self._streak = 0

    def step(self, t: float, action: str, allowed: Callable[[str], bool]) -> str | None:
        """Feed the filtered action at `t` ("" = none); return the command to send, if any.

        `allowed(action)` says whether the action may become a command now (arming); an
        action that is not allowed fires nothing and changes no debounce state.
        """
        self._streak = self._streak + 1 if action == self._previous else 1
        self._previous = action
        if self.latched is not None:
            if action == self.latched:
                self._gone_since = None
            else:
                if self._gone_since is None:
                    self._gone_since = t
                if t - self._gone_since >= self.release_s:
                    self.latched = None
                    self._gone_since = None
        if not action or self._streak < self.confirm_by_command.get(action, self.confirm):
            return None
        if self.last_fire_t is not None and t - self.last_fire_t < self.debounce_s:
            return None
        if action == self.latched:
            last = self.last_fire_t
            due = self.repeat_s is not None and last is not None and t - last >= self.repeat_s
            if not due:
                return None
        if not allowed(action):
            return None
        self.latched = action
        self.last_fire_t = t
        self._gone_since = None
        return action

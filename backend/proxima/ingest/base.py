"""The `FrameSource` interface every camera or replay stream implements.

A source is an iterable of `Frame`s with a visible `StreamState`. State changes follow a
fixed set of allowed transitions (a bug elsewhere shows up as an error, not as a source
that claims to be live after it ended) and are reported to listeners, so the engine can
publish them as `StreamEvent`s; a source itself publishes nothing.
"""

from __future__ import annotations

import logging
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from proxima.types import Frame, StreamState

log = logging.getLogger(__name__)

S = StreamState

# Which state may follow which. ENDED is final; a state never "changes" to itself.
ALLOWED_TRANSITIONS: dict[StreamState, frozenset[StreamState]] = {
    S.CONNECTING: frozenset({S.LIVE, S.RECONNECTING, S.ENDED}),
    S.LIVE: frozenset({S.STALLED, S.RECONNECTING, S.ENDED}),
    S.STALLED: frozenset({S.LIVE, S.RECONNECTING, S.ENDED}),
    S.RECONNECTING: frozenset({S.LIVE, S.ENDED}),
    S.ENDED: frozenset(),
}


class SourceError(RuntimeError):
    """A source cannot be opened or cannot go on (bad URI, missing or non-video file,
    unreachable camera, malformed replay CSV). The message names what and why."""


class InvalidTransition(RuntimeError):
    """A source tried a state change that `ALLOWED_TRANSITIONS` forbids (a bug)."""


@dataclass(frozen=True)
class StateChange:
    """One state change of a source, as given to `on_state` listeners.

    `t` is the stream time of the newest frame seen so far (0.0 before the first frame);
    `detail` says why (e.g. the error that made an RTSP stream reconnect).
    """

    uri: str
    previous: StreamState
    state: StreamState
    detail: str
    t: float


StateListener = Callable[[StateChange], None]


class FrameSource(ABC):
    """Iterable of `Frame`s from one stream, with a state and listeners for its changes.

    Use it as a context manager, or call `close()`, so reader threads and devices are
    released. Iterating ends when the source reaches `ENDED`; if it ended because of an
    error it could not recover from, iteration raises `SourceError` (also kept in
    `error`).
    """

    def __init__(self, uri: str, on_state: StateListener | None = None) -> None:
        self.uri = uri
        self._state = StreamState.CONNECTING
        self._detail = ""
        self._error: str | None = None
        self._last_t = 0.0
        self._state_lock = threading.RLock()
        self._listeners: list[StateListener] = []
        if on_state is not None:
            self._listeners.append(on_state)

    # -- state --------------------------------------------------------------------------
    @property
    def state(self) -> StreamState:
        """Current `StreamState`."""
        return self._state

    @property
    def detail(self) -> str:
        """Why the source is in its current state ("" when there is nothing to say)."""
        return self._detail

    @property
    def error(self) -> str | None:
        """The error that ended the source, or None if it ended normally or is running."""
        return self._error

    def add_listener(self, listener: StateListener) -> None:
        """Call `listener(StateChange)` on every later state change. It runs in the
        thread that changes the state (a reader thread for live sources), so it must be
        quick and must not block, e.g. `EventBus.publish`."""
        with self._state_lock:
            self._listeners.append(listener)

    def _set_state(self, state: StreamState, detail: str = "") -> bool:
        """Move to `state` if it differs from the current one; returns whether it moved.

        Raises:
            InvalidTransition: when the move is not in `ALLOWED_TRANSITIONS`.
        """
        with self._state_lock:
            previous = self._state
            if state == previous:
                self._detail = detail or self._detail  # same state, newer reason
                return False
            if state not in ALLOWED_TRANSITIONS[previous]:
                raise InvalidTransition(f"{self.uri}: {previous} -> {state} is not allowed")
            self._state = state
            self._detail = detail
            change = StateChange(self.uri, previous, state, detail, self._last_t)
            listeners = list(self._listeners)
        for listener in listeners:
            try:
                listener(change)
            except Exception:  # a broken listener must not kill the reader thread
                log.exception("state listener of %s failed", self.uri)
        return True

    def _advance(self, state: StreamState, detail: str = "") -> bool:
        """Like `_set_state`, but a no-op once ENDED: a reader thread racing `close()`
        must not fail on its last frame."""
        with self._state_lock:
            if self._state == StreamState.ENDED:
                return False
            return self._set_state(state, detail)

    def _end(self, error: str | None = None) -> None:
        """Move to ENDED (once), remembering `error` when the end is a failure."""
        with self._state_lock:
            if self._state == StreamState.ENDED:
                return
            if error is not None:
                self._error = error
            self._set_state(StreamState.ENDED, error or "")

    def _raise_if_failed(self) -> None:
        if self._error is not None:
            raise SourceError(self._error)

    # -- iteration and lifetime ---------------------------------------------------------
    @abstractmethod
    def _frames(self) -> Iterator[Frame]:
        """Yield the frames; subclasses implement this."""

    def __iter__(self) -> Iterator[Frame]:
        for frame in self._frames():
            self._last_t = frame.t
            yield frame
        self._raise_if_failed()

    def close(self) -> None:
        """Release the stream (threads, devices) and move to ENDED. Safe to call twice."""
        self._end()

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.uri!r}, state={self._state})"

"""Promoting a checkpoint into the running live engine, after checking the new model fits
it: every stream's classifier is swapped through the engine's own hook
(`Engine.swap_classifier`), which each stream thread applies before its next frame."""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from proxima.types import GESTURES

if TYPE_CHECKING:
    from proxima.engine import Engine

# How long `promote` waits for the streams to confirm the swap: a running stream does at
# its next frame; one without frames right now (a camera reconnecting) does later.
CONFIRM_TIMEOUT_S = 5.0


class EnginePromoter:
    """`proxima.api.interfaces.ModelPromoter` for a `proxima.engine.Engine`."""

    def __init__(self, engine: Engine, initial: str | Path | None = None) -> None:
        self._engine = engine
        self._lock = threading.Lock()
        self._active: str | None = str(initial) if initial else None
        if self._active is None:
            from proxima.gesture.classifier import default_checkpoint

            self._active = str(default_checkpoint())

    def attach(self, engine: Engine) -> None:
        """Promote into `engine` from now on (the console restarted its engine)."""
        with self._lock:
            self._engine = engine

    def active_checkpoint(self) -> str | None:
        return self._active

    def promote(self, checkpoint_path: str) -> dict[str, Any]:
        """Load the checkpoint and swap it into every stream; returns the streams, the
        window and the streams that have not confirmed the swap yet (`pending`).

        Raises:
            ValueError: not a gesture checkpoint, or one whose window or labels differ
                from what the engine runs.
        """
        from proxima.engine import load_classifier

        try:
            clf = load_classifier(checkpoint_path)
        except (FileNotFoundError, ValueError) as exc:
            raise ValueError(f"{checkpoint_path}: {exc}") from None
        if tuple(clf.labels) != GESTURES:
            raise ValueError(f"{checkpoint_path}: labels {clf.labels} differ from {GESTURES}")
        with self._lock:
            engine = self._engine
            names = [spec.name for spec in engine.specs]
            for name in names:
                window = engine.classifier(name).window
                if window != clf.window:
                    raise ValueError(
                        f"{checkpoint_path}: window {clf.window} differs from stream "
                        f"{name}'s {window}"
                    )
            swaps = engine.swap_classifier(clf)
            self._active = checkpoint_path
        deadline = time.monotonic() + CONFIRM_TIMEOUT_S
        pending = [s.stream for s in swaps if not s.wait(max(deadline - time.monotonic(), 0.0))]
        return {"streams": sorted(names), "window": clf.window, "pending": sorted(pending)}

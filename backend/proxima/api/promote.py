"""Promoting a checkpoint into the running live engine: every stream's classifier is
replaced between two classifications (an attribute swap the stream thread picks up at
its next window), after checking the new model fits the engine."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

from proxima.types import GESTURES


class EnginePromoter:
    """`proxima.api.interfaces.ModelPromoter` for a `proxima.engine.Engine`."""

    def __init__(self, engine: Any, initial: str | Path | None = None) -> None:
        self.engine = engine
        self._lock = threading.Lock()
        self._active: str | None = str(initial) if initial else None
        if self._active is None:
            from proxima.gesture.classifier import default_checkpoint

            self._active = str(default_checkpoint())

    def active_checkpoint(self) -> str | None:
        return self._active

    def promote(self, checkpoint_path: str) -> dict[str, Any]:
        """Load the checkpoint and swap it into every stream.

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
            for name, pipeline in self.engine.pipelines.items():
                old = pipeline.classifier
                if getattr(old, "window", clf.window) != clf.window:
                    raise ValueError(
                        f"{checkpoint_path}: window {clf.window} differs from stream "
                        f"{name}'s {old.window}"
                    )
            for pipeline in self.engine.pipelines.values():
                pipeline.classifier = clf
            self._active = checkpoint_path
        return {"streams": sorted(self.engine.pipelines), "window": clf.window}

"""Promoting a checkpoint into the running live engine, after checking the new model fits
it: every stream's classifier is swapped through the engine's own hook
(`Engine.swap_classifier`), which each stream thread applies before its next frame.

A model may also be promoted for some streams only (a calibration for one camera, the
Calibration page): those streams keep it until the next promotion for every stream
(or a rollback) replaces every stream's model; an engine restart re-applies it."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from proxima.types import GESTURES

if TYPE_CHECKING:
    from proxima.engine import Engine

log = logging.getLogger(__name__)

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
        self._streams: dict[str, str] = {}  # stream -> its own model (promoted for it)

    def attach(self, engine: Engine) -> None:
        """Promote into `engine` from now on (the console restarted its engine), and put
        each stream's own model back into it."""
        from proxima.engine import load_classifier

        with self._lock:
            self._engine = engine
            for stream, path in self._streams.items():
                try:
                    engine.swap_classifier(load_classifier(path), streams=[stream])
                except (FileNotFoundError, ValueError, KeyError) as exc:
                    log.warning("stream %s keeps the common model: %s", stream, exc)

    def active_checkpoint(self, stream: str | None = None) -> str | None:
        """The model `stream` runs (its own if one was promoted for it), else the one
        promoted for every stream."""
        if stream is not None and stream in self._streams:
            return self._streams[stream]
        return self._active

    def stream_checkpoints(self) -> dict[str, str]:
        """The streams that run a model of their own, and its path."""
        with self._lock:
            return dict(self._streams)

    def promote(self, checkpoint_path: str, streams: Sequence[str] | None = None) -> dict[str, Any]:
        """Load the checkpoint and swap it into every stream (clearing the streams' own
        models), or into `streams` only; returns the streams, the window and the streams
        that have not confirmed the swap yet (`pending`).

        Raises:
            ValueError: not a gesture checkpoint, one whose window or labels differ from
                what the engine runs, or an unknown stream.
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
            every = [spec.name for spec in engine.specs]
            names = every if streams is None else list(streams)
            unknown = sorted(set(names) - set(every))
            if unknown:
                raise ValueError(f"no stream {', '.join(unknown)} in the live engine")
            for name in names:
                window = engine.classifier(name).window
                if window != clf.window:
                    raise ValueError(
                        f"{checkpoint_path}: window {clf.window} differs from stream "
                        f"{name}'s {window}"
                    )
            swaps = engine.swap_classifier(clf, streams=None if streams is None else names)
            if streams is None:
                self._active = checkpoint_path
                self._streams.clear()
            else:
                self._streams.update(dict.fromkeys(names, checkpoint_path))
        deadline = time.monotonic() + CONFIRM_TIMEOUT_S
        pending = [s.stream for s in swaps if not s.wait(max(deadline - time.monotonic(), 0.0))]
        return {"streams": sorted(names), "window": clf.window, "pending": sorted(pending)}


# The audit actions that changed the live model; the newest `ok` one names the model in
# use, so the history and the model kept over a restart come from the audit trail.
CHANGE_ACTIONS = ("model.promote", "model.rollback")
# A model promoted for one stream (a calibration); the newest change for every stream
# replaces it.
STREAM_ACTION = "model.promote_stream"


def promotion_history(audit: Any, limit: int = 50) -> list[dict[str, Any]]:
    """The live model's changes, newest first: when, who, what (`action`), the model
    (`checkpoint`, its name in models/), the one it replaced (`previous`), the figures
    both had and the override reason, from the audit log's ok promote/rollback rows."""
    rows = audit.query(action="model", outcome="ok", limit=500)
    out = []
    for r in rows:
        if r.action not in CHANGE_ACTIONS:
            continue
        out.append(
            {
                "id": r.id,
                "ts": r.ts,
                "by": r.actor,
                "action": r.action.split(".", 1)[1],
                "checkpoint": r.target,
                "previous": r.detail.get("previous_name") or "",
                "figures": r.detail.get("figures"),
                "previous_figures": r.detail.get("previous_figures"),
                "override_reason": r.detail.get("override_reason") or "",
            }
        )
        if len(out) >= limit:
            break
    return out


def restore_promoted(promoter: EnginePromoter, audit: Any, models_dir: Path) -> str | None:
    """Put the model promoted before a restart back into the engine (the newest ok
    change in the audit log), so a restart keeps the supervisor's choice. Returns its
    name, or None when there was none, it is already running, or it is gone (logged)."""
    changes = promotion_history(audit, limit=1)
    if not changes:
        return None
    name = changes[0]["checkpoint"]
    path = Path(name) if Path(name).is_absolute() else Path(models_dir) / name
    active = promoter.active_checkpoint()
    if active and Path(active).resolve() == path.resolve():
        return None
    if not path.is_file():
        log.warning("model %s promoted before the restart is gone; running %s", name, active)
        return None
    try:
        promoter.promote(str(path))
    except ValueError as exc:
        log.warning("could not restore the promoted model %s: %s", name, exc)
        return None
    log.info("restored the promoted model %s", name)
    return name


def restore_stream_models(promoter: EnginePromoter, audit: Any, models_dir: Path) -> list[str]:
    """Put back the models promoted for single streams before a restart: per stream, its
    newest ok `model.promote_stream` row newer than the newest change for every stream.
    Returns "stream: model" for each one restored; a model gone is logged and skipped."""
    rows = audit.query(action="model", outcome="ok", limit=500)  # newest first
    restored: list[str] = []
    seen: set[str] = set()
    for r in rows:
        if r.action in CHANGE_ACTIONS:
            break  # older per-stream models were replaced by this change
        if r.action != STREAM_ACTION:
            continue
        stream = str(r.detail.get("stream") or "")
        if not stream or stream in seen:
            continue
        seen.add(stream)
        path = Path(r.target) if Path(r.target).is_absolute() else Path(models_dir) / r.target
        if not path.is_file():
            log.warning("model %s promoted for stream %s is gone", r.target, stream)
            continue
        try:
            promoter.promote(str(path), streams=[stream])
        except ValueError as exc:
            log.warning("could not restore %s for stream %s: %s", r.target, stream, exc)
            continue
        restored.append(f"{stream}: {r.target}")
    return restored

"""The live recognition engine: per-stream pipelines (source -> pose -> window ->
classifier -> filter), a time-ordered merge into the decision path (arbiter, debounce,
arming), typed events on an `EventBus` and a JSONL event writer. Stitched replay streams
and their scoring are `proxima.evaluation`.

Public API: `Engine` (with its hooks: frame taps, classifier swap), `StreamSpec`,
`EngineSettings`, `StreamPipeline`, `ClassifierSwap`, `Tap`, `TimeOrderedMerge`,
`JsonlWriter`, `PoseWindow`.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

# Lazy exports, so that registering `proxima recognize` does not import pydantic, torch
# and the rest for every other subcommand.
_EXPORTS = {
    "ClassifierSwap": "stream",
    "Engine": "runner",
    "EngineSettings": "config",
    "JsonlWriter": "jsonl",
    "PoseWindow": "window",
    "StreamPipeline": "stream",
    "StreamSpec": "config",
    "StreamStats": "runner",
    "Tap": "taps",
    "TimeOrderedMerge": "merge",
    "load_classifier": "runner",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(import_module(f"proxima.engine.{_EXPORTS[name]}"), name)
    raise AttributeError(name)

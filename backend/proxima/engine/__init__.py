"""The live recognition engine: per-stream pipelines (source -> pose -> window ->
classifier -> filter), a time-ordered merge into the decision path (arbiter, debounce,
arming), typed events on an `EventBus`, a JSONL event writer, and the stitching tool
that builds replay streams with a ground-truth script for tests and benchmarks.

Public API: `Engine`, `StreamSpec`, `EngineSettings`, `StreamPipeline`,
`TimeOrderedMerge`, `JsonlWriter`, `PoseWindow`.
"""

from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.jsonl import JsonlWriter
from proxima.engine.merge import TimeOrderedMerge
from proxima.engine.runner import Engine, StreamStats, load_classifier
from proxima.engine.stream import StreamPipeline
from proxima.engine.window import PoseWindow

__all__ = [
    "Engine",
    "EngineSettings",
    "JsonlWriter",
    "PoseWindow",
    "StreamPipeline",
    "StreamSpec",
    "StreamStats",
    "TimeOrderedMerge",
    "load_classifier",
]

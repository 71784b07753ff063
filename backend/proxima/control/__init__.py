"""From recognitions to commands: the moving-average filter, the debounce, arming and the
priority arbiter across the streams that watch the operator.

Public API: `ControlSettings` (`AVERAGE_RULE`), `MovingAverageFilter`, `HandEvidence`,
`CommandGate`, `Arming`, `PriorityArbiter`, `EvidenceAccumulator` (`decision_filter`),
`Sight`, `CommandController`, `StreamUpdate`, `WindowEvidence`. Everything runs on stream time.
"""

from proxima.control.accumulate import (
    DecisionFilter,
    EvidenceAccumulator,
    decide_window,
    decision_filter,
)
from proxima.control.arbiter import Handover, PriorityArbiter, Sight
from proxima.control.arming import ABORT_GESTURE, ARM_GESTURE, Arming
from proxima.control.config import AVERAGE_RULE, ControlSettings
from proxima.control.controller import (
    SAFE_COMMAND,
    CommandController,
    StreamUpdate,
    WindowEvidence,
)
from proxima.control.evidence import HandEvidence
from proxima.control.gate import CommandGate
from proxima.control.smoothing import FilteredAction, MovingAverageFilter

__all__ = [
    "ABORT_GESTURE",
    "ARM_GESTURE",
    "AVERAGE_RULE",
    "SAFE_COMMAND",
    "Arming",
    "CommandController",
    "CommandGate",
    "ControlSettings",
    "DecisionFilter",
    "EvidenceAccumulator",
    "FilteredAction",
    "HandEvidence",
    "Handover",
    "MovingAverageFilter",
    "PriorityArbiter",
    "Sight",
    "StreamUpdate",
    "WindowEvidence",
    "decide_window",
    "decision_filter",
]

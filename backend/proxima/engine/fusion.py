"""Fusion across streams: every camera that sees the operator adds its evidence to each
stream's decision; the priority arbiter still decides which stream drives.

With `EngineSettings.fusion = "on"` each stream's classified window carries a
`WindowEvidence` (`window_evidence`): its log-probabilities (the classifier's
probabilities are calibrated by the classifier itself: `GestureClassifier` applies the
checkpoint's temperature), and a weight, the mean visibility of the operator's arms
(shoulders, elbows, wrists) over the window, 0 below `fusion_min_visibility`. In the
decision path (`FusedDecisions`, between the time-ordered merge and the controller),
each stream's window is fused with the newest window of every other stream that sees
the operator, ended at most `fusion_max_age_s` before it and made by a classifier with
the same labels:

    fused = softmax(sum_i w_i * log p_i),   w_i = weight_i / max_j weight_j

(a product of experts, tempered by how well each camera sees the arms: agreeing views
sharpen, a poorly seen one counts less). A window whose own top probability reaches
`fusion_overrule_below` (default 0: every window) is fused only with the windows that
agree with its top label: the other cameras may sharpen it but not overrule it, since a
camera that reads a gesture wrongly is often just as sure (side views under z jitter,
docs/experiments.md "Fusion"; 0.9 and 1 gave more wrong commands there). The fused
vector goes through that stream's own fused decision rule (the stream's own kind,
`decision_filter`, emptied whenever the stream's own one is) and the hand evidence,
and its action replaces the stream's in the update; the controller then does what it
always does, so only the driving stream's action counts and every command goes to the
controlled drone. With `fusion_arms` false, while control is disarmed `have_command` is
the stream's own decision, fused or not: the other cameras speed up the commands, not
the arming.

The thumb gestures (`all_clear`, `not_clear`): a window that does not see the operator's
hand cannot tell them apart, so when some contributing window does see the hand, the
others' probabilities of the two are pooled (each gets their mean), and only those
windows decide between them; the fused action withholds them only if no contributing
window sees the hand. A stream alone (or with nobody else seeing the operator) decides
exactly as without fusion.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from proxima.control import (
    ARM_GESTURE,
    CommandController,
    ControlSettings,
    DecisionFilter,
    Sight,
    StreamUpdate,
    WindowEvidence,
    decide_window,
    decision_filter,
)
from proxima.control.evidence import THUMB_GESTURES
from proxima.engine.config import EngineSettings
from proxima.types import Event

ARMS = (11, 12, 13, 14, 15, 16)  # MediaPipe shoulders, elbows, wrists


def arm_visibility(visibility: np.ndarray) -> float:
    """Mean visibility of the arms' landmarks over a window (`visibility` (W, 33))."""
    return float(np.mean(np.asarray(visibility)[:, ARMS]))


def log_probs(probs: np.ndarray) -> np.ndarray:
    """The renormalised log-probabilities of one window (zeros clipped)."""
    z = np.log(np.clip(np.asarray(probs, dtype=np.float64), 1e-12, 1.0))
    return z - _logsumexp(z)


def window_evidence(
    probs: np.ndarray,
    visibility: np.ndarray,
    withheld: Sequence[str],
    labels: Sequence[str],
    min_visibility: float,
    restarted: bool,
) -> WindowEvidence:
    """One classified window (`probs` over `labels`, the window's `visibility` (W, 33))
    as fusion reads it; see the module for the weight."""
    seen = arm_visibility(visibility)
    return WindowEvidence(
        labels=tuple(labels),
        probs=np.asarray(probs, dtype=np.float64),
        log_probs=log_probs(probs),
        weight=seen if seen >= min_visibility else 0.0,
        withheld=tuple(withheld),
        restarted=restarted,
    )


@dataclass(frozen=True)
class Fused:
    """One stream's window fused with the others': `probs` over the labels, the gestures
    withheld, and the weight of each contributing stream (its own first)."""

    probs: np.ndarray
    withheld: tuple[str, ...]
    weights: dict[str, float]


def _top(e: WindowEvidence) -> str:
    """The window's top label, the thumb gestures counted as one (a window that does not
    see the hand cannot tell them apart)."""
    label = e.labels[int(np.argmax(e.probs))]
    return "thumb" if label in THUMB_GESTURES else label


def fuse(
    own: tuple[str, WindowEvidence],
    others: Sequence[tuple[str, WindowEvidence]],
    overrule_below: float = 1.0,
) -> Fused:
    """Fuse one stream's window with other streams' (see the module). The others must
    have the same labels and a weight > 0; the own window counts only if its weight is
    > 0, and alone it gives its own probabilities unchanged. While the own window's top
    probability reaches `overrule_below`, only the others that agree with its top label
    count (they may sharpen a confident view, not overrule it)."""
    name, mine = own
    if mine.weight > 0.0 and float(np.max(mine.probs)) >= overrule_below:
        others = [(n, e) for n, e in others if _top(e) == _top(mine)]
    parts = [(n, e) for n, e in [own, *others] if e.weight > 0.0]
    if not parts or (len(parts) == 1 and parts[0][0] == name):
        return Fused(mine.probs, mine.withheld, {name: mine.weight})
    top = max(e.weight for _, e in parts)
    labels = mine.labels
    thumbs = [labels.index(g) for g in THUMB_GESTURES if g in labels]
    judged = any(not e.withheld for _, e in parts)  # a view sees the hand, its arm raised
    total = np.zeros(len(labels))
    for _, e in parts:
        lp = e.log_probs
        if judged and e.withheld and len(thumbs) == 2:
            lp = lp.copy()
            lp[thumbs] = np.log(np.mean(np.exp(lp[thumbs])))  # no preference between them
        total += (e.weight / top) * lp
    probs = np.exp(total - _logsumexp(total))
    withheld = () if judged else parts[0][1].withheld  # then every part withholds them
    return Fused(probs, withheld, {n: round(e.weight, 3) for n, e in parts})


def _logsumexp(z: np.ndarray) -> float:
    m = float(np.max(z))
    return m + float(np.log(np.sum(np.exp(z - m))))


FusedListener = Callable[[str, float, Fused], None]


class FusedDecisions:
    """Sits between the time-ordered merge and the controller: replaces each classified
    update's action by the fused decision (see the module) and passes every update on.

    `listener(stream, t, fused)` (optional, e.g. a benchmark) sees every fused window.
    Runs in the merge's single decision thread, in stream-time order."""

    def __init__(
        self,
        controller: CommandController,
        control: ControlSettings | None = None,
        settings: EngineSettings | None = None,
        listener: FusedListener | None = None,
    ) -> None:
        self.controller = controller
        self.control = control or controller.settings
        self.settings = settings or EngineSettings()
        self.listener = listener
        self._newest: dict[str, tuple[float, WindowEvidence]] = {}
        self._filters: dict[str, DecisionFilter] = {}

    @property
    def active(self) -> str:
        """The driving stream (the controller's)."""
        return self.controller.active

    def process(self, update: StreamUpdate) -> list[Event]:
        """Fuse `update`'s window, if it has one, and give it to the controller."""
        stream = update.stream
        if update.ended or update.sight < Sight.PARTIAL:
            self._newest.pop(stream, None)  # it sees nobody: it contributes nothing
        evidence = update.evidence
        if evidence is not None and not update.ended and update.action is not None:
            update = self._fused_update(update, evidence)
        return self.controller.process(update)

    def _fused_update(self, update: StreamUpdate, evidence: WindowEvidence) -> StreamUpdate:
        stream, t = update.stream, update.t
        self._newest[stream] = (t, evidence)
        others = [
            (name, e)
            for name, (when, e) in self._newest.items()
            if name != stream
            and t - when <= self.settings.fusion_max_age_s
            and e.weight > 0.0
            and e.labels == evidence.labels
        ]
        fused = fuse((stream, evidence), others, self.settings.fusion_overrule_below)
        filt = self._filters.get(stream)
        if filt is None or filt.labels != evidence.labels:
            filt = self._filters[stream] = decision_filter(self.control, evidence.labels)
        if evidence.restarted:
            filt.reset()
        decision, action = decide_window(filt, t, fused.probs, fused.withheld)
        if (
            not self.settings.fusion_arms
            and not self.controller.arming.armed
            and ARM_GESTURE in (action, update.action)
        ):
            action = update.action or ""  # arming is the stream's own decision
        if self.listener is not None:
            self.listener(stream, t, fused)
        return StreamUpdate(stream, t, update.sight, action, decision.confidence, evidence=evidence)

"""The evidence rule: a leaky running sum of calibrated log-likelihood ratios per gesture.

The moving average asks three windows in a row for an averaged probability of 0.9. Under
camera noise a gesture the classifier names consistently at 0.6-0.85 never gets there,
and a lower threshold lets short confident blips through. Here each recognition adds,
for every gesture c, the log-odds of its calibrated probability,
llr_c = log p_c - log(1 - p_c) (clipped to +-`clip`), to a score that leaks with a
half-life of `half_life_s` stream seconds and never falls below 0 (a CUSUM): a gesture
named at 0.7 gains 0.85 a window and fires after a few, one named at 0.97 after two;
a gesture the classifier keeps below 0.5 only loses, so a mix where no gesture holds the
majority never fires. The action is the gesture of the highest score once that reaches
`threshold` (or its own entry in `thresholds`). `prior` weighs a gesture's probability
before the log-odds (then renormalised), which multiplies its odds by the weight: doubt
between `have_command` (a re-arm while armed, which moves no drone) and a motion is
settled towards the one that does nothing. Evidence accrues per stream second, not
per recognition: a recognition adds its log-odds times the seconds since the previous
one over `REFERENCE_INTERVAL_S` (stride 5 at 30 fps, where the settings were tuned), so
a 15 fps camera, with half the recognitions, arms as fast as a 30 fps one (counted per
recognition it could never reach 16 nats: 3 a window at most, halving every second).
A window that bridges a pause longer than training windows hold (`bridged`: the engine
keeps its window across a moment without the operator, engine/window.py) adds
`bridged_weight` of its evidence: the jump in it is outside what the model learned.
With `pair_margin` set, the thumb pair (`all_clear`, `not_clear`: one raised arm, thumb up
or down) is decided in two steps, as the classifier finds it: a window that is sure the
arm gives one of the two but splits 0.6 / 0.4 between them adds nothing to either alone
(log-odds of 0.6 barely pass zero), so the pair's commands starve although the arm is
plain. Then the pair shares one score, fed by the log-odds of the two probabilities'
sum, and a signed running sum of log(p_all_clear / p_not_clear), each window's weighted
by the pair's probability and leaking at the same half-life, says which: the pair's
action is the gesture that sum favours by `pair_margin` nats, or none while it does not.
The probabilities should be calibrated
(the checkpoint's temperature, gesture/calibration.py) for the log-odds to mean what
they say. The score empties after a pause of `reset_after_s` or on `reset()`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np

from proxima.control.evidence import THUMB_GESTURES
from proxima.control.smoothing import FilteredAction, MovingAverageFilter

if TYPE_CHECKING:
    from proxima.control.config import ControlSettings

P_FLOOR = 1e-6  # probabilities are clipped to [P_FLOOR, 1 - P_FLOOR] before the log-odds
REFERENCE_INTERVAL_S = 5 / 30  # one recognition's worth of stream time (stride 5, 30 fps)


class DecisionFilter(Protocol):
    """What the stream pipeline needs of a decision rule over recognitions."""

    labels: tuple[str, ...]

    def reset(self) -> None: ...

    def update(self, t: float, probs: np.ndarray, bridged: bool = False) -> FilteredAction: ...

    def withhold(self, labels: Sequence[str]) -> None: ...


class EvidenceAccumulator:
    """Leaky CUSUM of calibrated log-odds per label (see the module)."""

    def __init__(
        self,
        labels: Sequence[str],
        threshold: float = 4.0,
        half_life_s: float = 1.0,
        clip: float = 3.0,
        reset_after_s: float = 1.0,
        thresholds: Mapping[str, float] | None = None,
        prior: Mapping[str, float] | None = None,
        bridged_weight: float = 1.0,
        pair_margin: float | None = None,
    ) -> None:
        if threshold <= 0 or half_life_s <= 0 or clip <= 0:
            raise ValueError(
                f"evidence rule: threshold, half-life and clip must be > 0, "
                f"got {threshold}, {half_life_s}, {clip}"
            )
        if not 0.0 <= bridged_weight <= 1.0:
            raise ValueError(f"evidence rule: bridged weight must be 0..1, got {bridged_weight}")
        if pair_margin is not None and pair_margin < 0:
            raise ValueError(f"evidence rule: pair margin must be >= 0, got {pair_margin}")
        self.bridged_weight = bridged_weight
        self.labels = tuple(labels)
        # (index of all_clear, index of not_clear) when the pair is decided in two steps
        self._pair = (
            tuple(self.labels.index(g) for g in THUMB_GESTURES)
            if pair_margin is not None and all(g in self.labels for g in THUMB_GESTURES)
            else None
        )
        self.pair_margin = pair_margin
        self.threshold = threshold
        self.thresholds = dict(thresholds or {})
        self.half_life_s = half_life_s
        self.clip = clip
        self.reset_after_s = reset_after_s
        self._need = np.array([self.thresholds.get(lab, threshold) for lab in self.labels])
        self.prior = dict(prior or {})
        if any(v <= 0 for v in self.prior.values()):
            raise ValueError(f"evidence rule: prior weights must be > 0, got {self.prior}")
        weights = np.array([self.prior.get(lab, 1.0) for lab in self.labels])
        self._weights = None if np.all(weights == 1.0) else weights
        self.reset()

    @classmethod
    def from_settings(cls, control: ControlSettings, labels: Sequence[str]) -> EvidenceAccumulator:
        return cls(
            labels,
            control.evidence_threshold,
            control.evidence_half_life_s,
            control.evidence_clip,
            control.filter_reset_s,
            control.evidence_threshold_by_command,
            control.evidence_prior_by_command,
            control.evidence_bridged_weight,
            control.evidence_pair_margin,
        )

    def reset(self) -> None:
        """Forget all evidence."""
        self.score = np.zeros(len(self.labels))
        self.pair_ratio = 0.0  # signed evidence for all_clear over not_clear (`pair_margin`)
        self._last_t: float | None = None

    def update(self, t: float, probs: np.ndarray, bridged: bool = False) -> FilteredAction:
        """Add one recognition (probabilities over `labels`; `bridged`: its window holds a
        bridged pause) and decide. `confidence` is the leading gesture's evidence as a
        share of its threshold (1 = it passes).

        Raises:
            ValueError: `probs` does not have one entry per label.
        """
        p = np.asarray(probs, dtype=np.float64).reshape(-1)
        if p.shape[0] != len(self.labels):
            raise ValueError(f"expected {len(self.labels)} probabilities, got {p.shape[0]}")
        if self._last_t is not None and t - self._last_t > self.reset_after_s:
            self.reset()
        weighed = p  # the prior's odds: a gesture's probability times its weight
        if self._weights is not None:
            weighed = p * self._weights / float(np.dot(p, self._weights))
        dt = 0.0 if self._last_t is None else max(t - self._last_t, 0.0)
        decay = 0.5 ** (dt / self.half_life_s)
        # the stream time this recognition stands for (the first: one reference interval);
        # rounded so that 30 fps at stride 5 weighs exactly 1
        weight = 1.0 if self._last_t is None else round(dt / REFERENCE_INTERVAL_S, 6)
        if bridged:
            weight *= self.bridged_weight
        self._last_t = t
        q = np.clip(weighed, P_FLOOR, 1.0 - P_FLOOR)
        if self._pair is not None:  # the thumb's evidence, then the pair as one gesture
            a, b = self._pair
            ratio = float(np.clip(np.log(q[a]) - np.log(q[b]), -self.clip, self.clip))
            q[[a, b]] = both = min(q[a] + q[b], 1.0 - P_FLOOR)
            self.pair_ratio = decay * self.pair_ratio + weight * both * ratio
        llr = np.clip(np.log(q) - np.log1p(-q), -self.clip, self.clip)
        self.score = np.maximum(decay * self.score + weight * llr, 0.0)
        share = self.score / self._need
        best = int(np.argmax(share))
        action = self.labels[best] if share[best] >= 1.0 else ""
        if self._pair is not None and best in self._pair and action:
            action = self._pair_action()
        return FilteredAction(t=t, action=action, confidence=float(min(share[best], 1.0)), probs=p)

    def _pair_action(self) -> str:
        """The thumb gesture the pair's signed evidence favours by the margin, else none."""
        margin = self.pair_margin or 0.0
        if self.pair_ratio >= margin:
            return THUMB_GESTURES[0]
        if self.pair_ratio <= -margin:
            return THUMB_GESTURES[1]
        return ""

    def withhold(self, labels: Sequence[str]) -> None:
        """The newest window cannot give `labels` (the hand evidence: the hand unseen, or
        its arm down): their evidence so far was a guess or rest, so it is dropped, and a
        thumb gesture needs `threshold` from windows that see the hand raised in a row."""
        for label in labels:
            self.score[self.labels.index(label)] = 0.0
        if self._pair is not None and any(g in labels for g in THUMB_GESTURES):
            self.pair_ratio = 0.0


def decide_window(
    rule: DecisionFilter,
    t: float,
    probs: np.ndarray,
    withheld: Sequence[str],
    bridged: bool = False,
) -> tuple[FilteredAction, str]:
    """One recognition through `rule` (`bridged`: its window holds a bridged pause); the
    gestures the window cannot tell (`withheld`) are neither the action nor kept as
    evidence. Returns the decision and the action."""
    decision = rule.update(t, probs, bridged)
    rule.withhold(withheld)
    return decision, "" if decision.action in withheld else decision.action


def decision_filter(control: ControlSettings, labels: Sequence[str]) -> DecisionFilter:
    """The decision rule `control.decision` names: the moving average or the evidence rule."""
    if control.decision == "evidence":
        return EvidenceAccumulator.from_settings(control, labels)
    return MovingAverageFilter.from_settings(control, labels)

"""Settings of the decision path: filter, threshold, debounce, arming and arbitration.

Every duration is in stream seconds (the frames' clock), so a replay at any speed decides
the same. Defaults were tuned with `bench/command_latency.py` (see docs/recognition.md).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

from proxima.types import GESTURES


def _known_gestures(counts: dict) -> dict:
    # A misspelt key would otherwise leave that command on the general setting.
    unknown = sorted(set(counts) - set(GESTURES))
    if unknown:
        raise ValueError(f"unknown gesture {', '.join(unknown)}; known: {', '.join(GESTURES)}")
    return counts


# Per-gesture count of agreeing decisions; keys are gesture names, counts at least 1.
ConfirmByCommand = Annotated[
    dict[str, Annotated[int, Field(ge=1)]], AfterValidator(_known_gestures)
]
# Per-gesture averaged probability an action needs, in place of `threshold`.
ThresholdByCommand = Annotated[
    dict[str, Annotated[float, Field(gt=0.0, le=1.0)]], AfterValidator(_known_gestures)
]
# Per-gesture evidence (nats) an action needs under the evidence rule.
ThresholdByEvidence = Annotated[
    dict[str, Annotated[float, Field(gt=0.0)]], AfterValidator(_known_gestures)
]
DecisionRule = Literal["average", "evidence"]
# The evidence rule's per-command thresholds (nats; the rest need `evidence_threshold`):
# arming alone moves no drone, and the side views name have_command at 0.6-0.9; 12 with
# the shipped ensemble gives 6 points more of the commands asked for under `field` than
# 17.5 for 2 more wrong acting commands in 10 h (docs/experiments.md, "Twenty-ninth session").
# The abort (hover, disarm) at 12 too: a missed one leaves the drone on its last command,
# a false one only hovers it; the left view names it at 0.8-0.9 with dips (+0.5-0.9
# points clean and under `field`, "Thirty-fifth session")
# The thumb pair at 12 too: its command also needs `EVIDENCE_PAIR_MARGIN` of thumb evidence,
# and the right view reads `all_clear` at 0.5-0.7 beside `move_downward`; +0.3-1.8 points
# clean, +0.2-0.8 under `field`, no wrong command more on two model sets ("Thirty-fifth
# session")
# `land` at 24 (with 5 agreeing decisions, `CONFIRM_BY_COMMAND`): a wrong landing ends the
# flight, and `land_direction`'s pause with both hands low reads as `land`; a clipped sum
# is a time floor too (8 recognitions at least, 1.3 s at 30 fps) ("Thirty-sixth session")
EVIDENCE_BY_COMMAND = {
    "have_command": 12.0,
    "wave_off": 12.0,
    "all_clear": 12.0,
    "not_clear": 12.0,
    "land": 24.0,
}
# Its per-command odds weights: doubt between have_command (while armed a re-arm, which
# moves no drone) and a motion goes to the former; measured over 30 h of held-out
# streams per condition (docs/experiments.md, "Twenty-seventh session")
EVIDENCE_PRIOR_BY_COMMAND = {"have_command": 2.0}
# all_clear / not_clear decided in two steps (the pair as one gesture, then the thumb by
# this many nats of their running log-ratio): on 4 h of held-out streams per condition and
# two model sets, +0.9-3.2 points of the commands asked for clean and +1.7-2.2 under
# `field`, one more wrong command in 16 h (all_clear read as not_clear: a hold for a
# resume) (docs/experiments.md, "Thirty-fifth session")
EVIDENCE_PAIR_MARGIN = 12.0
# Agreeing decisions per command (the rest: `confirm`): a wrong landing ends the flight, so
# `land` needs 5 (0.8 s) on its 24 nats: 9 on 18 gave 3 `land_direction` -> `land` in 16 h of
# held-out streams on two model sets, 5 on 24 none, for the same commands and 0.1-0.2 s
# off the p95 under `field`; 5 on 18 gave tens ("Thirty-sixth session").
# `move_downward` 3 (0.5 s): an arm coming down (all_clear's, move_to_right's) reads as it
# for a moment; 3-4 of 9-10 wrong acting commands under `field` in 4 h of held-out streams
# gone, on two model sets, for under 0.1 point of commands ("Thirty-fifth session")
CONFIRM_BY_COMMAND = {"land": 5, "move_downward": 3}
# all_clear / not_clear raise the arm to shoulder height: a window whose thumb-hand wrist
# stays below a quarter of the way from hip to shoulder is rest, which the classifier (no
# rest class) reads as the pair. A hanging arm reaches 0.16 at most (twice the measured
# jitter, eye level); a camera 45 degrees up foreshortens the right view's raised arm, and
# half the way passed only 35-52 % of its pair windows there, a quarter 73-91 %
# (docs/experiments.md, "Thirty-fifth session")
THUMB_RAISE = 0.25
# The operator's hand that all_clear / not_clear need in view; "off": no check.
ThumbHand = Literal["right", "left", "off"]


class ControlSettings(BaseModel):
    """How recognitions become commands.

    The paper averages three recognitions and waits 10 s between commands (10.4 s
    response). The default is the evidence rule: half-life 2 s, clip 3, one decision,
    tuned for the held-out 30-frame seeds on streams captured at 15-30 fps
    (`bench/evidence_retune.py`, checked with `bench/decision_check.py`), with the base
    threshold at 18 nats and `have_command` at 12 since the shipped model is an ensemble
    of five seeds, whose mean passes fewer wrong readings (`bench/operating_curve.py`;
    docs/recognition.md, docs/experiments.md "Thirtieth session"). `AVERAGE_RULE` below
    is the moving average as it was tuned (the default until 2026-12-05).
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    decision: DecisionRule = Field(
        "evidence",
        description="how recognitions become an action: 'evidence' (a leaky sum of "
        "calibrated log-odds, control/accumulate.py) or 'average' (the moving average and "
        "its threshold; tuned on untempered probabilities with confirm 2: `AVERAGE_RULE`)",
    )
    filter_size: int = Field(3, ge=1, description="recognitions in the moving average")
    threshold: float = Field(
        0.9, ge=0.0, le=1.0, description="averaged probability an action needs"
    )
    threshold_by_command: ThresholdByCommand = Field(
        default_factory=lambda: {"wave_off": 0.7},
        description="per-command `threshold`, e.g. {'wave_off': 0.7}: the abort (hover and "
        "disarm) is safe to give on less evidence, and missing it is not",
    )
    evidence_threshold: float = Field(
        18.0, gt=0.0, description="evidence rule: summed log-odds (nats) an action needs"
    )
    evidence_threshold_by_command: ThresholdByEvidence = Field(
        default_factory=lambda: dict(EVIDENCE_BY_COMMAND),
        description="evidence rule: per-command `evidence_threshold`, e.g. {'have_command': "
        "12}: arming alone moves no drone, and the side views name it at 0.6-0.9",
    )
    evidence_prior_by_command: ThresholdByEvidence = Field(
        default_factory=lambda: dict(EVIDENCE_PRIOR_BY_COMMAND),
        description="evidence rule: per-command weight on the calibrated probability (its "
        "odds times the weight) before the log-odds, e.g. {'have_command': 2}: doubt between "
        "have_command, which moves no drone, and a motion is settled towards it",
    )
    evidence_half_life_s: float = Field(
        2.0, gt=0.0, description="evidence rule: stream seconds in which evidence halves"
    )
    evidence_clip: float = Field(
        3.0,
        gt=0.0,
        description="evidence rule: most log-odds one recognition adds or takes per 1/6 s "
        "of stream (it weighs the seconds since the previous one)",
    )
    evidence_bridged_weight: float = Field(
        0.5,
        ge=0.0,
        le=1.0,
        description="evidence rule: share of its evidence a window adds when it holds a "
        "pause the engine bridged (longer than training windows hold, 0.25 s): at 1, "
        "bridging gave 3 times the wrong commands under `field`",
    )
    evidence_pair_margin: float | None = Field(
        EVIDENCE_PAIR_MARGIN,
        ge=0.0,
        description="evidence rule: decide all_clear / not_clear in two steps, the pair's "
        "summed probability as one gesture and then which thumb, by this many nats of "
        "their running log-ratio (None: two gestures like the rest)",
    )
    confirm: int = Field(
        1, ge=1, description="consecutive filtered decisions that must agree before a command"
    )
    confirm_by_command: ConfirmByCommand = Field(
        default_factory=lambda: dict(CONFIRM_BY_COMMAND),
        description="per-command `confirm`, e.g. {'land': 5}: a command that ends the "
        "flight may ask for a longer agreement than the others",
    )
    debounce_s: float = Field(2.0, ge=0.0, description="least time between two commands")
    release_s: float = Field(
        4.0,
        ge=0.0,
        description="how long an action must be gone before the same command may fire again",
    )
    repeat_s: float | None = Field(
        None, gt=0.0, description="re-send a held command after this long (None: never)"
    )
    filter_reset_s: float = Field(
        1.0, gt=0.0, description="a pause between recognitions this long empties the filter"
    )
    thumb_hand: ThumbHand = Field(
        "right",
        description="the operator's hand for all_clear and not_clear, which only its thumb "
        "tells apart: a window that does not see it commands neither ('off': no check)",
    )
    hand_visibility: float = Field(
        0.5, ge=0.0, le=1.0, description="finger visibility that counts as the hand seen"
    )
    thumb_raise: float | None = Field(
        THUMB_RAISE,
        ge=0.0,
        description="all_clear and not_clear raise the thumb hand's arm: a window whose "
        "wrist never rises this share of the way from the hip to the shoulder commands "
        "neither (None: no check)",
    )
    idle_disarm_s: float = Field(
        60.0, gt=0.0, description="disarm after this long without a command"
    )
    hold_s: float = Field(
        1.0, ge=0.0, description="how long the driving stream may lose the operator"
    )
    regain_s: float = Field(
        1.0, ge=0.0, description="how long a stream must see the operator to take control"
    )
    rearm_on_handover: bool = Field(
        True, description="a handover disarms: the operator repeats have_command"
    )


# The moving-average rule as `bench/command_latency.py` tuned it (three recognitions
# averaged to 0.9, two agreeing decisions); it expects untempered probabilities (a
# checkpoint with temperature 1): a fitted temperature sharpens the average into wrong
# commands (docs/recognition.md).
# land on nine agreeing decisions, as the average rule was tuned with
AVERAGE_RULE = ControlSettings(
    decision="average", confirm=2, confirm_by_command={**CONFIRM_BY_COMMAND, "land": 9}
)

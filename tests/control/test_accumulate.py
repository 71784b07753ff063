"""The evidence rule (control/accumulate.py) on real outputs of the pre-capture model
(tests/data) for real clips under the capture model's jitter, smoothed as the engine
smooths replays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from proxima.control import (
    ControlSettings,
    EvidenceAccumulator,
    MovingAverageFilter,
    decide_window,
    decision_filter,
)
from proxima.control.evidence import THUMB_GESTURES
from proxima.gesture.capture import condition, live_windows
from proxima.gesture.windows import temporal_parts

# A model trained without capture augmentation, unsure on noisy input (tests/data/README.md).
NO_CAPTURE = Path(__file__).resolve().parents[1] / "data" / "gesture-no-capture.pt"


@pytest.fixture(scope="module")
def classifier():  # type: ignore[no-untyped-def]
    import torch

    from proxima.gesture.classifier import GestureClassifier

    torch.set_num_threads(1)
    return GestureClassifier.load(NO_CAPTURE)


def outputs(classifier, clip, level: int, seed: int = 0):  # type: ignore[no-untyped-def]
    """(probabilities, window end times) of the engine's windows (stride 5) of `clip`'s
    test part at `level` x the measured jitter, through the live One Euro filter."""
    from proxima.evaluation.robust_training import smooth

    part = temporal_parts(clip, 60)[1]
    cap = smooth(condition("jitter", level).apply_clip(part, np.random.default_rng(seed)))
    xyz, _, t = live_windows(cap, 60, 5)
    return classifier.predict(xyz, aspect=clip.aspect), t


def first(rule, labels, probs, t, gesture):  # type: ignore[no-untyped-def]
    for i, p in enumerate(probs):
        if rule.update(float(t[i]), p).action == gesture:
            return i
    return None


def test_a_noisy_but_consistent_have_command_arms_fast(laser_clips, classifier) -> None:
    clip = next(c for c in laser_clips if c.gesture == "have_command" and c.view == "f")
    probs, t = outputs(classifier, clip, level=2)
    hc = probs[:, classifier.labels.index("have_command")]
    assert hc.min() < 0.7 and hc.mean() < 0.9  # noisy: windows well under the 0.9 threshold
    # The rule's first setting (4 nats): the shipped 16 suits the calibrated 30-frame
    # models, this unsure pre-capture model names have_command at 0.5-0.9.
    control = ControlSettings(
        decision="evidence", evidence_threshold=4.0, evidence_threshold_by_command={}
    )
    rule = decision_filter(control, classifier.labels)
    assert isinstance(rule, EvidenceAccumulator)
    fired = first(rule, classifier.labels, probs, t, "have_command")
    avg = first(MovingAverageFilter(classifier.labels, 3, 0.9), classifier.labels, probs, t,
                "have_command")  # fmt: skip
    assert fired is not None and t[fired] - t[0] <= 1.0  # within a second of the first window
    assert avg is None or fired < avg


def test_a_noisy_mix_never_fires(laser_clips, classifier) -> None:
    # Consecutive windows from the front-view clips of different gestures in turn: every
    # output is a real, often confident one, but no gesture holds from window to window.
    front = [c for c in laser_clips if c.view == "f"]
    runs = [outputs(classifier, c, level=2, seed=k)[0] for k, c in enumerate(front)]
    n = min(len(r) for r in runs)
    mixed = np.stack([runs[k % len(runs)][k // len(runs)] for k in range(n * len(runs))])
    assert (mixed.max(axis=1) > 0.9).mean() > 0.3  # confident windows among them
    t = np.arange(len(mixed)) / 6.0  # stride 5 at 30 fps
    for order in (mixed, mixed[::-1]):
        rule = EvidenceAccumulator(classifier.labels)
        actions = {rule.update(float(ti), p).action for ti, p in zip(t, order, strict=True)}
        assert actions == {""}, actions


def test_evidence_leaks_and_resets() -> None:
    labels = ("a", "b", "c")
    rule = EvidenceAccumulator(labels, threshold=4.0, half_life_s=1.0)
    p = np.array([0.8, 0.1, 0.1])  # log-odds log 4 = 1.39 a window
    got = [rule.update(k / 6, p).action for k in range(4)]
    assert got == ["", "", "", "a"]  # 1.39, 2.62, 3.72 (leaking 11% a window), 4.70
    # evidence halves per half-life: after 2 s of nothing it is a quarter
    before = rule.score[0]
    rule.update(4 / 6 + 0.9, np.full(3, 1 / 3))  # log-odds of 1/3 < 0: it falls further
    assert rule.score[0] < before * 0.6
    rule.update(10.0, p)  # a pause over filter_reset_s: a fresh start
    assert rule.score[0] == pytest.approx(np.log(4.0))
    with pytest.raises(ValueError, match="threshold"):
        EvidenceAccumulator(labels, threshold=0.0)
    with pytest.raises(ValueError, match="unknown gesture"):
        ControlSettings(evidence_threshold_by_command={"lnad": 3.0})


def test_a_thumb_gesture_counts_only_windows_that_see_the_hand() -> None:
    labels = ("all_clear", "not_clear", "hover")
    rule = EvidenceAccumulator(labels, threshold=4.0)
    p = np.array([0.9, 0.05, 0.05])  # all_clear at log 9 = 2.2 nats a window
    for k in range(6):  # hand hidden: the guess is neither the action nor kept
        _, action = decide_window(rule, k / 6, p, THUMB_GESTURES)
        assert action == "" and rule.score[0] == 0.0
    # seen from now on: it needs the threshold from these windows alone
    got = [decide_window(rule, (6 + k) / 6, p, [])[1] for k in range(2)]
    assert got == ["", "all_clear"]
    # the moving average keeps its window (confirm asks for seen windows in a row)
    avg = MovingAverageFilter(labels, 3, 0.8)
    assert [decide_window(avg, k / 6, p, THUMB_GESTURES if k < 2 else [])[1]
            for k in range(3)] == ["", "", "all_clear"]  # fmt: skip


def test_evidence_accrues_per_stream_second_whatever_the_frame_rate() -> None:
    # Stride 5 at 30 fps recognises every 1/6 s, at 15 fps every 1/3 s: the same
    # confident gesture fires at about the same stream time, at 16 nats as well.
    labels = ("a", "b", "c")
    p = np.array([0.9, 0.05, 0.05])  # 2.2 nats per 1/6 s
    fired = {}
    for fps in (30, 15, 10):
        rule = EvidenceAccumulator(labels, threshold=16.0, half_life_s=1.0)
        dt = 5 / fps
        fired[fps] = next(k * dt for k in range(100) if rule.update(k * dt, p).action == "a")
    assert fired[30] == pytest.approx(13 / 6)  # the 14th recognition
    assert abs(fired[15] - fired[30]) <= 1 / 3 and abs(fired[10] - fired[30]) <= 0.5


def test_a_prior_weight_multiplies_a_gestures_odds_and_settles_doubt_towards_it() -> None:
    labels = ("have_command", "move_ahead", "hover")
    p = np.array([0.4, 0.55, 0.05])  # a side view's doubt between the two
    plain = EvidenceAccumulator(labels, threshold=1.5, half_life_s=100.0, clip=10.0)
    weighed = EvidenceAccumulator(
        labels, threshold=1.5, half_life_s=100.0, clip=10.0, prior={"have_command": 2.0}
    )
    plain.update(0.0, p)
    out = weighed.update(0.0, p)
    # odds 0.4 / 0.6 doubled: log-odds + log 2, and move_ahead's odds fall with it
    assert weighed.score[0] == pytest.approx(np.log(0.4 / 0.6) + np.log(2.0))
    assert weighed.score[1] == pytest.approx(np.log(0.55 / (1 - 0.55)) - np.log(1.4), abs=0.2)
    assert weighed.score[1] < plain.score[1]
    np.testing.assert_allclose(out.probs, p)  # the recognition itself is reported as it was
    got = [weighed.update(k / 6, p).action for k in range(1, 12)]
    assert "have_command" in got and "move_ahead" not in got
    assert "move_ahead" in [plain.update(k / 6, p).action for k in range(1, 12)]
    with pytest.raises(ValueError, match="prior weights"):
        EvidenceAccumulator(labels, prior={"hover": 0.0})
    with pytest.raises(ValueError, match="unknown gesture"):
        ControlSettings(evidence_prior_by_command={"have_comand": 2.0})
    rule = decision_filter(ControlSettings(evidence_prior_by_command={"have_command": 2.0}), labels)
    assert isinstance(rule, EvidenceAccumulator) and rule.prior == {"have_command": 2.0}


def test_a_window_across_a_bridged_pause_adds_part_of_its_evidence() -> None:
    labels = ("a", "b", "c")
    p = np.array([0.8, 0.1, 0.1])  # log 4 = 1.39 nats per 1/6 s
    full = EvidenceAccumulator(labels, threshold=100.0, half_life_s=1e9)
    half = EvidenceAccumulator(labels, threshold=100.0, half_life_s=1e9, bridged_weight=0.5)
    for k, bridged in enumerate([False, True, True, False]):
        full.update(k / 6, p, bridged)
        half.update(k / 6, p, bridged)
    assert full.score[0] == pytest.approx(4 * np.log(4.0))
    assert half.score[0] == pytest.approx(3 * np.log(4.0))  # 1 + 0.5 + 0.5 + 1 windows
    # the shipped setting, through decide_window as the stream pipeline calls it
    rule = decision_filter(ControlSettings(), labels)
    assert isinstance(rule, EvidenceAccumulator) and rule.bridged_weight == 0.5
    decide_window(rule, 0.0, p, [], bridged=True)
    assert rule.score[0] == pytest.approx(0.5 * np.log(4.0))
    with pytest.raises(ValueError, match="bridged weight"):
        EvidenceAccumulator(labels, bridged_weight=1.5)


def test_the_thumb_pair_is_decided_as_one_gesture_then_by_its_running_log_ratio() -> None:
    labels = ("all_clear", "not_clear", "hover")
    doubt = np.array([0.35, 0.55, 0.10])  # a front view: sure of the arm, unsure of the thumb
    t = np.arange(40) / 6
    # each alone: log-odds of 0.55 is 0.2 nats a window, short of 4 nats at any length
    plain = EvidenceAccumulator(labels, threshold=4.0, half_life_s=1.0)
    assert {plain.update(float(ti), doubt).action for ti in t} == {""}
    # two steps: the pair gains log 9 = 2.2 nats a window; the signed sum gains
    # 0.9 x log(0.35 / 0.55) = -0.41 a window (leaking 11 %) and passes -2 at the 7th
    rule = EvidenceAccumulator(labels, threshold=4.0, half_life_s=1.0, pair_margin=2.0)
    got = [rule.update(float(ti), doubt).action for ti in t]
    assert got[:6] == [""] * 6 and set(got[6:]) == {"not_clear"}
    assert rule.score[0] == rule.score[1] > 4.0 and rule.pair_ratio < -2.0
    # a window that does not see the hand drops the thumb's evidence, not only the pair's
    decide_window(rule, 40 / 6, doubt, THUMB_GESTURES)
    assert rule.pair_ratio == 0.0 and rule.score[0] == rule.score[1] == 0.0
    # an arm whose thumb flips from window to window never commands either
    flip = EvidenceAccumulator(labels, threshold=4.0, half_life_s=1.0, pair_margin=2.0)
    acts = {flip.update(float(ti), doubt if k % 2 else doubt[[1, 0, 2]]).action
            for k, ti in enumerate(t)}  # fmt: skip
    assert acts == {""} and flip.score[0] > 4.0
    # the setting reaches the rule: 12 nats by default, None for two gestures like the rest
    on = decision_filter(ControlSettings(), labels)
    assert isinstance(on, EvidenceAccumulator) and on.pair_margin == 12.0
    off = decision_filter(ControlSettings(evidence_pair_margin=None), labels)
    assert isinstance(off, EvidenceAccumulator) and off._pair is None
    with pytest.raises(ValueError, match="pair margin"):
        EvidenceAccumulator(labels, pair_margin=-1.0)

"""Gesture motions: every gesture defined, scripts of several gestures in one continuous
clip, handedness, determinism."""

from __future__ import annotations

import numpy as np

from proxima.gesture.geometry import torso_length
from proxima.synth.anthropometry import nominal_body, sample_body
from proxima.synth.body import body_landmarks
from proxima.synth.gestures import SPECS
from proxima.synth.motion import IDLE_LABEL, draw_gesture, perform
from proxima.types import GESTURES


def test_every_gesture_has_a_motion() -> None:
    assert sorted(SPECS) == sorted(GESTURES)
    for name, spec in SPECS.items():
        moving = [m for m in (spec.right, spec.left) if m.peak is not None]
        assert spec.repeated == bool(moving), name  # static gestures move no arm
        assert spec.arms and spec.plane and spec.extent and spec.signal


def test_a_script_is_one_continuous_clip() -> None:
    rng = np.random.default_rng(4)
    body = nominal_body()
    script = ["hover", "land", "move_to_left", IDLE_LABEL, "wave_off"]
    steps = [draw_gesture(IDLE_LABEL, rng, duration_s=1.0)]
    steps += [draw_gesture(g, rng, duration_s=3.0 if g == IDLE_LABEL else None) for g in script]
    perf = perform(steps, rng, fps=30.0)
    assert [s[0] for s in perf.segments] == [IDLE_LABEL, *script]
    for (_, start, onset, end), (_, nxt, _, _) in zip(
        perf.segments, perf.segments[1:], strict=False
    ):
        assert start <= onset < end == nxt
    assert perf.segments[-1][3] == len(perf) == len(perf.labels)
    labels = list(perf.labels)
    for label, start, _, end in perf.segments:
        assert set(labels[start:end]) == {label}
    lm = body_landmarks(body, perf.posture)
    step = np.linalg.norm(np.diff(lm, axis=0), axis=-1).max(axis=1)  # metres a frame
    assert step.max() < 5.0 / 30  # no point faster than 5 m/s (a fast hand), anywhere
    # Moving from one gesture into the next is no faster than the gestures themselves.
    entries = np.zeros(len(step), bool)
    for _, start, onset, _ in perf.segments:
        entries[max(start - 1, 0) : onset] = True
    assert step[entries].max() <= step[~entries].max()


def test_handed_gestures_use_the_dominant_arm() -> None:
    for hand, moving, still in (("right", 16, 15), ("left", 15, 16)):
        rng = np.random.default_rng(0)
        body = sample_body(rng, handedness=hand)  # type: ignore[arg-type]
        perf = perform([draw_gesture("all_clear", rng, hand)], rng)  # type: ignore[arg-type]
        lm = body_landmarks(body, perf.posture)
        assert np.ptp(lm[:, moving, 2]) > 0.4  # the dominant wrist rises and falls
        assert np.ptp(lm[:, still, 2]) < 0.1
    # Direction gestures do not follow the hand: move_to_left holds the left arm out.
    rng = np.random.default_rng(1)
    perf = perform([draw_gesture("move_to_left", rng, "left")], rng)
    lm = body_landmarks(nominal_body(), perf.posture)
    assert np.ptp(lm[:, 15, 1]) < np.ptp(lm[:, 16, 1])


def test_a_seed_gives_the_same_performance() -> None:
    def run(seed: int) -> np.ndarray:
        rng = np.random.default_rng(seed)
        return body_landmarks(
            nominal_body(), perform([draw_gesture("slow_down", rng)], rng).posture
        )

    np.testing.assert_array_equal(run(5), run(5))
    assert not np.array_equal(run(5), run(6))


def test_have_command_has_a_lower_forward_variant() -> None:
    """The variant raises the fist ahead to just above the shoulder (as LASER's operator
    does), the written form above the head; gestures without one ignore `variant`."""
    body = nominal_body()

    def top_of_wrist(variant: bool) -> np.ndarray:
        rng = np.random.default_rng(3)
        draw = draw_gesture("have_command", rng, variant=variant)
        assert draw.variant is variant
        lm = body_landmarks(body, perform([draw], rng).posture)
        rel = (lm[:, 16] - lm[:, 12]) / torso_length(lm).item()  # (fwd, left, up) in torsos
        return rel[np.argmax(rel[:, 2])]

    written, variant = top_of_wrist(False), top_of_wrist(True)
    assert written[2] > 0.7  # above the head
    assert 0.0 < variant[2] < 0.6 and variant[0] > 0.6  # ahead, just above the shoulder
    a = draw_gesture("hover", np.random.default_rng(5), variant=True)
    assert a == draw_gesture("hover", np.random.default_rng(5)) and not a.variant

"""The body's joint limits hold for every generated pose, measured from the landmarks."""

from __future__ import annotations

import numpy as np
import pytest

from proxima.synth.anthropometry import nominal_body, sample_body
from proxima.synth.body import Placement, Posture, body_landmarks, world_landmarks
from proxima.synth.joints import (
    ARM_LIMITS,
    ELBOW,
    ELEVATION,
    PLANE,
    ROTATION,
    arm_angles,
    clamp_arm,
    limit_violations,
)
from proxima.synth.motion import IDLE_LABEL, draw_gesture, perform
from proxima.types import GESTURES


def test_measured_angles_are_the_angles_posed() -> None:
    """Plane, elevation, rotation and elbow measured back from landmarks equal the angles
    the body was posed with (inside the limits), for both arms."""
    rng = np.random.default_rng(0)
    lo, hi = ARM_LIMITS.ranges().T
    angles = clamp_arm(rng.uniform(lo, hi, size=(400, 7)))
    angles[:, ELBOW] = np.maximum(angles[:, ELBOW], 20)  # rotation is defined when bent
    angles[:, ELEVATION] = np.clip(angles[:, ELEVATION], 15, 165)
    angles = clamp_arm(angles)
    body = nominal_body()
    posture = Posture.standing(len(angles), angles[0])
    posture.right_arm[:] = angles
    posture.left_arm[:] = angles[::-1]
    lm = world_landmarks(body, posture, Placement(north=3.0, east=-2.0, heading_deg=137.0))
    for side, want in (("right", angles), ("left", angles[::-1])):
        got = arm_angles(lm, side)
        np.testing.assert_allclose(got["elevation"], want[:, ELEVATION], atol=1e-6)
        np.testing.assert_allclose(got["elbow"], want[:, ELBOW], atol=1e-6)
        np.testing.assert_allclose(got["plane"], want[:, PLANE], atol=1e-6)
        np.testing.assert_allclose(got["rotation"], want[:, ROTATION], atol=1e-5)


def test_out_of_range_requests_are_clamped() -> None:
    body = nominal_body()
    wild = np.array(
        [
            [170.0, 179.0, 120.0, 175.0, 100.0, 40.0, 90.0],  # across, up, past limits
            [-120.0, 150.0, -100.0, -20.0, -100.0, -50.0, -90.0],
        ]
    )  # behind: extension
    posture = Posture.standing(2, wild[0])
    posture.right_arm[:] = wild
    lm = body_landmarks(body, posture)
    assert limit_violations(lm) == []
    a = arm_angles(lm, "right")
    assert a["elbow"][0] == pytest.approx(ARM_LIMITS.elbow[1])
    assert a["elevation"][1] == pytest.approx(ARM_LIMITS.extension_elevation)  # plane -90


def test_a_broken_pose_is_reported() -> None:
    """The checker itself catches a pose outside the limits (landmarks moved by hand)."""
    body = nominal_body()
    lm = body_landmarks(body, Posture.standing(1, np.array([20, 90, 0, 30, 0, 0, 0.0])))
    lm[0, 16] = lm[0, 14] + (lm[0, 14] - lm[0, 12])  # straight on: fine
    assert limit_violations(lm) == []
    lm[0, 16] = lm[0, 14] - 0.9 * (lm[0, 14] - lm[0, 12])  # forearm folded back: 170+ deg
    assert any("right elbow flexion" in p for p in limit_violations(lm))


@pytest.mark.parametrize("handedness", ["right", "left"])
def test_no_generated_gesture_breaks_the_limits(handedness: str) -> None:
    """Every gesture (and its variant, where it has one) on varied bodies, with the
    performance's random variation and idle transitions, stays inside the shoulder and
    elbow limits."""
    rng = np.random.default_rng(1 if handedness == "right" else 2)
    for k in range(4):
        body = sample_body(rng, handedness=handedness)  # type: ignore[arg-type]
        steps = [draw_gesture(IDLE_LABEL, rng, duration_s=0.5)]
        steps += [draw_gesture(g, rng, body.handedness, variant=k % 2 == 1) for g in GESTURES]
        perf = perform(steps, rng)
        lm = body_landmarks(body, perf.posture)
        assert limit_violations(lm) == []

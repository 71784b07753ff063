"""The synthetic operator's kinematic body: joint angles over time -> the 33 MediaPipe
pose landmarks in 3D.

Frames: the body is posed in its own frame (x forward, y left, z up, metres, origin on
the ground between the feet), then placed in the world, which is local NED (x north,
y east, z down) like the drone stack's positions, so a simulated drone's camera and the
operator share one frame. `Placement.heading_deg` is the way the operator faces,
clockwise from north, as a MAVLink yaw.

Landmark order and names are MediaPipe's BlazePose topology (`LANDMARK_NAMES`): face
points, shoulders to hands (pinky, index and thumb points), hips to feet (heel, foot
index). Where each point sits on the body follows `anthropometry.py`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from proxima.synth.anthropometry import BodyShape
from proxima.synth.joints import arm_directions, clamp_arm, torso_frame

LANDMARK_NAMES: tuple[str, ...] = (
    "nose",
    "left_eye_inner",
    "left_eye",
    "left_eye_outer",
    "right_eye_inner",
    "right_eye",
    "right_eye_outer",
    "left_ear",
    "right_ear",
    "mouth_left",
    "mouth_right",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_pinky",
    "right_pinky",
    "left_index",
    "right_index",
    "left_thumb",
    "right_thumb",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_foot_index",
    "right_foot_index",
)
FACE = tuple(range(11))
TORSO = (11, 12, 23, 24)
# Limb segments (landmark pairs) with the BodyShape field holding their radius.
LIMBS: tuple[tuple[int, int, str], ...] = (
    (11, 13, "upper_arm_radius"),
    (13, 15, "forearm_radius"),
    (12, 14, "upper_arm_radius"),
    (14, 16, "forearm_radius"),
    (23, 25, "thigh_radius"),
    (25, 27, "shank_radius"),
    (24, 26, "thigh_radius"),
    (26, 28, "shank_radius"),
)

# Hand points from the wrist: (along the hand axis in hand lengths, toward the thumb side
# in hand breadths, toward the palm in breadths). MediaPipe's pose model puts its pinky
# and index points close together about 0.13 torso lengths out along the forearm (LASER
# front view, medians; 0.01-0.04 apart across it) and the thumb point at 0.09, up to 0.05
# to the thumb's side.
HAND_POINTS = {"pinky": (0.42, -0.15, 0.0), "index": (0.43, 0.15, 0.0), "thumb": (0.31, 0.38, 0.1)}


@dataclass
class Posture:
    """A body pose per frame, T frames. Arms (T, 7) in `joints.ARM_DOF` order (degrees);
    `pelvis` (T, 3) shift of the hips' midpoint (metres, body frame); `trunk` (T, 3) lean
    forward, lean to the left, twist to the left (degrees); `head` (T, 3) turn to the left,
    nod down, tilt to the left (degrees, relative to the trunk); `knees` (T,) flexion."""

    right_arm: np.ndarray
    left_arm: np.ndarray
    pelvis: np.ndarray
    trunk: np.ndarray
    head: np.ndarray
    knees: np.ndarray

    def __len__(self) -> int:
        return len(self.right_arm)

    @classmethod
    def standing(cls, n: int, arm: np.ndarray) -> Posture:
        """n frames of one arm pose on both sides, upright and still."""
        arms = np.broadcast_to(np.asarray(arm, np.float64), (n, 7)).copy()
        z3 = np.zeros((n, 3))
        return cls(arms, arms.copy(), z3, z3.copy(), z3.copy(), np.zeros(n))


@dataclass(frozen=True)
class Stance:
    """Where the feet stand: ankle-to-ankle distance (m) and toe-out (degrees per foot)."""

    foot_width: float = 0.2
    toe_out_deg: float = 8.0


@dataclass(frozen=True)
class Placement:
    """The operator in the world: ground point (NED metres) and heading (degrees)."""

    north: float = 0.0
    east: float = 0.0
    down: float = 0.0
    heading_deg: float = 0.0

    def to_world(self, points: np.ndarray) -> np.ndarray:
        """Body-frame points (x forward, y left, z up) -> NED."""
        h = np.deg2rad(self.heading_deg)
        c, s = np.cos(h), np.sin(h)
        fx, fy, fz = points[..., 0], -points[..., 1], -points[..., 2]  # forward, right, down
        out = np.stack([c * fx - s * fy, s * fx + c * fy, fz], axis=-1)
        return out + np.array([self.north, self.east, self.down])


def _rot(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotation matrices about a fixed unit axis by angles (T,) in radians."""
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    C = 1 - c
    m = np.empty((len(angle), 3, 3))
    m[:, 0] = np.stack([c + x * x * C, x * y * C - z * s, x * z * C + y * s], -1)
    m[:, 1] = np.stack([y * x * C + z * s, c + y * y * C, y * z * C - x * s], -1)
    m[:, 2] = np.stack([z * x * C - y * s, z * y * C + x * s, c + z * z * C], -1)
    return m


_X, _Y, _Z = np.eye(3)


def _two_bone_knee(
    hip: np.ndarray, ankle: np.ndarray, thigh: float, shank: float, forward: np.ndarray
) -> np.ndarray:
    """Knee positions (T, 3) between hip and ankle, bending toward `forward`."""
    d_vec = ankle - hip
    d = np.linalg.norm(d_vec, axis=-1, keepdims=True)
    d = np.clip(d, abs(thigh - shank) + 1e-6, thigh + shank - 1e-6)
    e = d_vec / np.linalg.norm(d_vec, axis=-1, keepdims=True)
    a = (thigh**2 - shank**2 + d**2) / (2 * d)
    h = np.sqrt(np.maximum(thigh**2 - a**2, 0.0))
    n = forward - np.sum(forward * e, axis=-1, keepdims=True) * e
    n = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-9)
    return hip + a * e + h * n


def _leg_lengths(body: BodyShape) -> tuple[float, float]:
    thigh = float(
        np.hypot(body.hip_height - body.knee_height, (body.hip_width - body.knee_width) / 2)
    )
    return thigh, body.knee_height - body.ankle_height


def body_landmarks(body: BodyShape, posture: Posture, stance: Stance | None = None) -> np.ndarray:
    """(T, 33, 3) landmark positions in the body frame (x forward, y left, z up, metres).

    Arm angles are clamped to the joint limits first (`joints.clamp_arm`), so no pose
    leaves them whatever the motion asked for."""
    stance = stance or Stance()
    T = len(posture)
    H = body.stature
    out = np.zeros((T, 33, 3))
    thigh, shank = _leg_lengths(body)

    # Feet on the ground, toes turned out a little.
    toe = np.deg2rad(stance.toe_out_deg)
    for side, sgn in (("left", 1), ("right", -1)):
        ankle = np.array([0.0, sgn * stance.foot_width / 2, body.ankle_height])
        foot_dir = np.array([np.cos(toe), sgn * np.sin(toe), 0.0])
        a_i, h_i, f_i = (27, 29, 31) if side == "left" else (28, 30, 32)
        out[:, a_i] = ankle
        out[:, h_i] = ankle - 0.2 * body.foot * foot_dir - [0, 0, 0.75 * body.ankle_height]
        out[:, f_i] = ankle + 0.72 * body.foot * foot_dir - [0, 0, 0.8 * body.ankle_height]

    # Pelvis: its height follows the knees' bend (the feet stay planted).
    k = np.deg2rad(posture.knees)
    reach = np.sqrt(thigh**2 + shank**2 + 2 * thigh * shank * np.cos(k))  # hip to ankle
    spread = (body.hip_width - stance.foot_width) / 2
    pelvis = np.zeros((T, 3))
    pelvis[:, 2] = body.ankle_height + np.sqrt(np.maximum(reach**2 - spread**2, 1e-6))
    pelvis += posture.pelvis
    out[:, 23] = pelvis + np.array([0.0, body.hip_width / 2, 0.0])
    out[:, 24] = pelvis - np.array([0.0, body.hip_width / 2, 0.0])
    fwd = np.broadcast_to(_X, (T, 3))
    out[:, 25] = _two_bone_knee(out[:, 23], out[:, 27], thigh, shank, fwd)
    out[:, 26] = _two_bone_knee(out[:, 24], out[:, 28], thigh, shank, fwd)

    # Trunk: lean forward (about the left axis), lean left (about forward), twist.
    tr = np.deg2rad(posture.trunk)
    rot = _rot(_Y, tr[:, 0]) @ _rot(-_X, tr[:, 1]) @ _rot(_Z, tr[:, 2])
    up = rot @ _Z
    left = rot @ _Y
    mid = pelvis + body.torso * up
    out[:, 11] = mid + left * body.shoulder_width / 2
    out[:, 12] = mid - left * body.shoulder_width / 2

    # Arms in the torso frame the shoulder and hip landmarks define (joints.torso_frame).
    frame = torso_frame(out)  # (T, 3, 3) rows forward, left, up
    for side, s_i, arm in (("left", 11, posture.left_arm), ("right", 12, posture.right_arm)):
        d = arm_directions(clamp_arm(arm))
        mirror = np.array([1.0, 1.0 if side == "left" else -1.0, 1.0])
        world = {k: np.einsum("tij,ti->tj", frame, v * mirror) for k, v in d.items()}
        e_i, w_i = s_i + 2, s_i + 4
        out[:, e_i] = out[:, s_i] + body.upper_arm * world["u"]
        out[:, w_i] = out[:, e_i] + body.forearm * world["f"]
        for j, name in zip((s_i + 6, s_i + 8, s_i + 10), ("pinky", "index", "thumb"), strict=True):
            along, thumb, palm = HAND_POINTS[name]
            out[:, j] = out[:, w_i] + (
                body.hand * along * world["h"]
                + body.hand_breadth * (thumb * world["t"] + palm * world["p"])
            )

    # Head: pivots at the neck above the shoulders' midpoint, turns relative to the trunk.
    hd = np.deg2rad(posture.head)
    torso_to_body = np.transpose(frame, (0, 2, 1))  # columns: forward, left, up
    head_rot = torso_to_body @ _rot(_Z, hd[:, 0]) @ _rot(_Y, hd[:, 1]) @ _rot(-_X, hd[:, 2])
    pivot_up = 0.045 * H
    pivot = mid + up * pivot_up
    ez = body.eye_height - body.shoulder_height - pivot_up
    mz = ez + 0.75 * (body.chin_height - body.eye_height)  # the mouth, most of the way to the chin
    hw = body.head_width / 2
    face = np.array(
        [
            [0.064 * H, 0.0, ez - 0.031 * H],  # nose
            [0.056 * H, 0.010 * H, ez],
            [0.054 * H, 0.018 * H, ez],
            [0.049 * H, 0.027 * H, ez],
            [0.056 * H, -0.010 * H, ez],
            [0.054 * H, -0.018 * H, ez],
            [0.049 * H, -0.027 * H, ez],
            [0.0, hw, ez - 0.006 * H],
            [0.0, -hw, ez - 0.006 * H],  # ears
            [0.056 * H, 0.013 * H, mz],
            [0.056 * H, -0.013 * H, mz],  # mouth
        ]
    )
    out[:, :11] = pivot[:, None] + np.einsum("tij,kj->tki", head_rot, face)
    return out


def world_landmarks(
    body: BodyShape,
    posture: Posture,
    placement: Placement | None = None,
    stance: Stance | None = None,
) -> np.ndarray:
    """(T, 33, 3) landmark positions in the world (NED metres)."""
    return (placement or Placement()).to_world(body_landmarks(body, posture, stance))

"""Landmark layouts: MediaPipe's 33, OpenPose COCO-18, and their left/right twins."""

from __future__ import annotations

# MediaPipe BlazePose indices used below.
NOSE = 0
L_SHOULDER, R_SHOULDER = 11, 12
L_ELBOW, R_ELBOW = 13, 14
L_WRIST, R_WRIST = 15, 16
L_HIP, R_HIP = 23, 24
L_KNEE, R_KNEE = 25, 26
L_ANKLE, R_ANKLE = 27, 28
FEET = (27, 28, 29, 30, 31, 32)  # ankles, heels, foot tips

# OpenPose COCO-18 joint -> MediaPipe landmark; the neck (1) has no twin and is the
# shoulders' midpoint in the common skeleton.
OPENPOSE_TO_MEDIAPIPE: dict[int, int] = {
    0: 0,  # nose
    2: 12, 3: 14, 4: 16,  # right shoulder, elbow, wrist
    5: 11, 6: 13, 7: 15,  # left shoulder, elbow, wrist
    8: 24, 9: 26, 10: 28,  # right hip, knee, ankle
    11: 23, 12: 25, 13: 27,  # left hip, knee, ankle
    14: 5, 15: 2,  # right eye, left eye
    16: 8, 17: 7,  # right ear, left ear
}  # fmt: skip

# The common 2D skeleton both data sets share: these 17 MediaPipe landmarks (+ neck).
COMMON = tuple(sorted(OPENPOSE_TO_MEDIAPIPE.values()))

# Hand points of the pose model (pinky, index, thumb; left then right) and the wrist each
# hangs from. UAV-Gesture has no hands: its loader puts them on the wrist (offset 0).
HANDS = (17, 19, 21, 18, 20, 22)
HAND_WRIST = (15, 15, 15, 16, 16, 16)

# Each landmark's left/right twin (itself on the midline), for mirroring.
_PAIRS = [(1, 4), (2, 5), (3, 6), (7, 8), (9, 10)] + [(i, i + 1) for i in range(11, 33, 2)]
MIRROR: list[int] = list(range(33))
for _a, _b in _PAIRS:
    MIRROR[_a], MIRROR[_b] = _b, _a

# Bones for drawing and for features (pairs of MediaPipe indices) on the common skeleton.
BONES = [
    (11, 12), (11, 13), (13, 15), (12, 14), (14, 16), (11, 23), (12, 24), (23, 24),
    (23, 25), (25, 27), (24, 26), (26, 28), (0, 2), (0, 5), (2, 7), (5, 8),
]  # fmt: skip

"""Body proportions of the synthetic operator: adults of different statures and builds.

Sources:
- Segment lengths as fractions of stature H: Drillis & Contini (1966), as tabulated in
  D. A. Winter, *Biomechanics and Motor Control of Human Movement*, 4th ed. (Wiley, 2009),
  Fig. 4.1: upper arm 0.186 H, forearm 0.146 H, hand 0.108 H, foot 0.152 H, shoulder
  (acromion) height 0.818 H, chin 0.870 H, eyes 0.936 H, ankle 0.039 H, shoulder width
  0.259 H, hip width 0.191 H.
- Stature: 5th / 50th / 95th percentiles 1.649 / 1.759 / 1.869 m for men and
  1.518 / 1.618 / 1.724 m for women (R. L. Huston, *Principles of Biomechanics*, CRC
  Press, 2009); drawn from a normal distribution with those medians and the spread the
  percentiles give (sd = (p95 - p5) / 3.29).

Where pose estimators put their points is not where the anatomical tables measure. On
both shipped data sets (MediaPipe on the LASER operator, OpenPose on UAV-Gesture's 11
people) the shoulder landmarks are 0.65 torso lengths apart, the hip landmarks 0.37-0.40,
and the hip and knee points sit at 0.50 and 0.24 of the nose-to-ankle height: the pose
"hip" lies below the greater trochanter (0.530 H) and the pose "knee" below the joint
line (0.285 H). The landmark heights and widths below are those measured positions
(`LANDMARK_FRACTIONS`); the limb lengths are Drillis & Contini's.

The spread of each fraction between people of one stature is not in these tables: each
segment (and each vertical step between landmarks) is drawn here with a 3 % coefficient
of variation (an assumption), and a build factor
(0.94-1.08, also assumed) widens or narrows shoulders, hips and torso depth together.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np

Sex = Literal["female", "male"]
Hand = Literal["right", "left"]

# Stature percentiles (m): 5th, 50th, 95th (Huston 2009).
STATURE_PERCENTILES: dict[str, tuple[float, float, float]] = {
    "male": (1.649, 1.759, 1.869),
    "female": (1.518, 1.618, 1.724),
}

# Lengths as fractions of stature (Drillis & Contini 1966, via Winter 2009, Fig. 4.1).
SEGMENT_FRACTIONS: dict[str, float] = {
    "upper_arm": 0.186,
    "forearm": 0.146,
    "hand": 0.108,
    "foot": 0.152,
    "ankle_height": 0.039,
    "chin_above_shoulder": 0.870 - 0.818,
    "eye_above_chin": 0.936 - 0.870,
}

# Where the pose models' points sit, as fractions of stature (measured on LASER and
# UAV-Gesture, see the module docstring): the vertical steps between them (knee above
# ankle, hip above knee, shoulder above hip: knee at 0.245 H, hip at 0.465 H, shoulder
# at 0.818 H) and the widths between the left and right points.
LANDMARK_FRACTIONS: dict[str, float] = {
    "shank": 0.245 - 0.039,
    "thigh": 0.465 - 0.245,
    "torso": 0.818 - 0.465,
    "shoulder_width": 0.232,  # 0.65 torso lengths (Drillis & Contini biacromial: 0.259)
    "hip_width": 0.135,  # 0.38 torso lengths (bitrochanteric skin width: 0.191)
    "knee_width": 0.11,
    "head_width": 0.085,  # between the ears, 0.24 torso lengths on LASER
}

# Sizes for occlusion and the hand points (fractions of stature; typical adult values).
SHAPE_FRACTIONS: dict[str, float] = {
    "hand_breadth": 0.048,
    "torso_depth": 0.12,
    "upper_arm_radius": 0.024,
    "forearm_radius": 0.019,
    "thigh_radius": 0.04,
    "shank_radius": 0.028,
}

FRACTION_CV = 0.03  # per-person spread of each fraction (assumed)
BUILD_RANGE = (0.94, 1.08)  # slim .. broad (assumed)
LEFT_HANDED_SHARE = 0.2  # a bit above the population's ~10 %, so both sides are well seen


@dataclass(frozen=True)
class BodyShape:
    """One synthetic person: every length in metres."""

    sex: Sex
    handedness: Hand
    stature: float
    build: float
    upper_arm: float
    forearm: float
    hand: float
    hand_breadth: float
    foot: float
    ankle_height: float
    knee_height: float
    hip_height: float
    shoulder_height: float
    chin_height: float
    eye_height: float
    shoulder_width: float
    hip_width: float
    knee_width: float
    head_width: float
    torso_depth: float
    upper_arm_radius: float
    forearm_radius: float
    thigh_radius: float
    shank_radius: float

    @property
    def torso(self) -> float:
        """Vertical distance from the hip landmarks to the shoulder landmarks."""
        return self.shoulder_height - self.hip_height

    def to_dict(self) -> dict[str, float | str]:
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> BodyShape:
        return cls(**d)


def stature_sd(sex: Sex) -> float:
    lo, _, hi = STATURE_PERCENTILES[sex]
    return (hi - lo) / 3.29  # 5th to 95th percentile of a normal distribution


def nominal_body(stature: float = 1.70, sex: Sex = "male", handedness: Hand = "right") -> BodyShape:
    """The body of exactly the tabulated proportions (build 1.0)."""
    return _body(stature, 1.0, sex, handedness, lambda name: 1.0)


def sample_body(
    rng: np.random.Generator, sex: Sex | None = None, handedness: Hand | None = None
) -> BodyShape:
    """An adult drawn from the stature percentiles, with per-person proportions and build."""
    sex = sex or ("male" if rng.random() < 0.5 else "female")
    handedness = handedness or ("left" if rng.random() < LEFT_HANDED_SHARE else "right")
    _, median, _ = STATURE_PERCENTILES[sex]
    stature = float(np.clip(rng.normal(median, stature_sd(sex)), median - 0.25, median + 0.25))
    build = float(rng.uniform(*BUILD_RANGE))
    factors = {
        name: float(np.clip(rng.normal(1.0, FRACTION_CV), 0.9, 1.1))
        for name in (*SEGMENT_FRACTIONS, *LANDMARK_FRACTIONS, *SHAPE_FRACTIONS)
    }
    return _body(stature, build, sex, handedness, factors.__getitem__)


_WIDE = {
    "shoulder_width",
    "hip_width",
    "knee_width",
    "torso_depth",
    "upper_arm_radius",
    "forearm_radius",
    "thigh_radius",
    "shank_radius",
}


def _body(
    stature: float, build: float, sex: Sex, handedness: Hand, factor: Callable[[str], float]
) -> BodyShape:
    v: dict[str, float] = {}
    for table in (SEGMENT_FRACTIONS, LANDMARK_FRACTIONS, SHAPE_FRACTIONS):
        for name, fraction in table.items():
            scale = build if name in _WIDE else 1.0
            v[name] = fraction * factor(name) * scale * stature
    # Heights are sums of the vertical steps, so they stay ordered whatever the draws.
    knee = v["ankle_height"] + v.pop("shank")
    hip = knee + v.pop("thigh")
    shoulder = hip + v.pop("torso")
    chin = shoulder + v.pop("chin_above_shoulder")
    eye = chin + v.pop("eye_above_chin")
    return BodyShape(
        sex=sex,
        handedness=handedness,
        stature=stature,
        build=build,
        knee_height=knee,
        hip_height=hip,
        shoulder_height=shoulder,
        chin_height=chin,
        eye_height=eye,
        **v,
    )

"""The 13 marshalling gestures as parametric arm motions.

Each gesture moves each arm between a `rest` pose and a `peak` pose (joint angles, see
`joints.ARM_DOF`), or holds `rest` (static gestures and the still arm of one-armed
ones). The definitions follow the UAV-Gesture paper's gestures (Perera et al. 2018),
which it took from the aircraft and helicopter handling signals (US Navy NAVAIR
00-80T-113 helicopter signals; EASA/EHEST helicopter ground signals; ICAO marshalling),
and are measured on the LASER recordings (MediaPipe landmarks of one operator, three
views) for which arm moves, in which plane, how far, and how fast: where a recording
departs from the written signal, the recording wins, because it is what the data
shows (e.g. `not_clear` raises the arm to shoulder height like `all_clear`, with the
thumb down instead of up, where the signal holds the hand below the waist).

Left and right follow the LASER labels (docs/synth.md and data-notes.md): in LASER's
`move_to_left` the operator's left arm is held out and the right arm swings over the
head toward it; UAV-Gesture's `move_to_left` is the mirror image. `handed` gestures are
made with the dominant arm (the right one for a right-handed operator; LASER's operator
uses the right); a left-handed operator makes them with the left arm.

The numbers come from fitting the joint angles to the LASER clips' elbow and wrist
positions (torso lengths from the shoulder; front view for sideways and vertical, side
views for forward), then checking the whole motion with a classifier trained on real
clips only (`bench/synth_agreement.py`). `have_command` is raised higher than LASER's
operator raises it (UAV-Gesture's people hold the fist near or above the head), and
`move_ahead` beckons higher too: both read as their gesture far more often so
(docs/synth.md). Half of a data set's `have_command` clips take its variant, the fist
raised ahead to just above the shoulder as LASER's operator does (`GestureSpec.variant`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def arm(
    plane: float = 20.0,
    elevation: float = 10.0,
    rotation: float = 0.0,
    elbow: float = 15.0,
    pronation: float = 10.0,
    wrist_dev: float = 0.0,
    wrist_flex: float = 0.0,
) -> np.ndarray:
    """One arm pose (7 angles, degrees) in `joints.ARM_DOF` order."""
    return np.array([plane, elevation, rotation, elbow, pronation, wrist_dev, wrist_flex])


# Arms hanging at the sides, elbows a little bent, palms toward the thighs.
IDLE = arm(plane=25, elevation=10, rotation=-10, elbow=18, pronation=10)


@dataclass(frozen=True)
class ArmMotion:
    """One arm's part: `rest`, or back and forth between `rest` and `peak`."""

    rest: np.ndarray
    peak: np.ndarray | None = None


@dataclass(frozen=True)
class GestureSpec:
    """A gesture's motion and its description (for docs/synth.md)."""

    name: str
    right: ArmMotion
    left: ArmMotion
    period_s: tuple[float, float] | None  # one repetition; None: static
    dwell: tuple[float, float] = (1.0, 1.6)  # 1 = sinusoid, larger = pauses at both ends
    handed: bool = False
    arms: str = ""
    plane: str = ""
    extent: str = ""
    signal: str = ""  # the written marshalling signal it comes from
    # Another way people make it: (right, left) arm motions that a data set draws instead
    # for part of its clips (`dataset.VARIANT_SHARE`).
    variant: tuple[ArmMotion, ArmMotion] | None = None

    @property
    def repeated(self) -> bool:
        return self.period_s is not None


_OUT = arm(plane=5, elevation=75, rotation=0, elbow=10, pronation=0)  # held out sideways

SPECS: dict[str, GestureSpec] = {
    s.name: s
    for s in (
        GestureSpec(
            "all_clear",
            right=ArmMotion(IDLE, arm(plane=24, elevation=90, rotation=60, elbow=20, pronation=0)),
            left=ArmMotion(IDLE),
            period_s=(1.3, 2.0),
            dwell=(1.6, 2.6),
            handed=True,
            arms="dominant arm; the other hangs",
            plane="sideways, 25 degrees forward of the frontal plane",
            extent="from hanging to shoulder height, thumb up",
            signal="hand raised, thumb up (affirmative / all clear)",
        ),
        GestureSpec(
            "not_clear",
            right=ArmMotion(
                IDLE, arm(plane=0, elevation=88, rotation=-40, elbow=30, pronation=40, wrist_dev=10)
            ),
            left=ArmMotion(IDLE),
            period_s=(1.3, 2.0),
            dwell=(1.6, 2.6),
            handed=True,
            arms="dominant arm; the other hangs",
            plane="sideways (frontal plane)",
            extent="from hanging to shoulder height, thumb down (LASER; the written signal "
            "holds the hand below the waist)",
            signal="arm held out, hand below waist level, thumb turned downwards (negative)",
        ),
        GestureSpec(
            "have_command",
            right=ArmMotion(IDLE, arm(plane=80, elevation=150, rotation=0, elbow=45, pronation=0)),
            left=ArmMotion(IDLE),
            # LASER's raise is a quick flick from a hanging arm: a fast swing with long
            # pauses at its ends imitates it (the closed-loop simulator, docs/synth.md).
            period_s=(0.8, 1.1),
            dwell=(2.0, 3.0),
            handed=True,
            arms="dominant arm; the other hangs",
            plane="forward (sagittal)",
            extent="from hanging to the fist raised ahead above the head",
            signal="fist raised (I have command)",
            # The variant: the fist raised ahead to just above the shoulder, as LASER's
            # operator does (side views' top: elbow 0.47 torso lengths ahead at shoulder
            # height, wrist 0.88 ahead and 0.3 up).
            variant=(
                ArmMotion(IDLE, arm(plane=65, elevation=100, rotation=0, elbow=30, pronation=0)),
                ArmMotion(IDLE),
            ),
        ),
        GestureSpec(
            "hover",
            right=ArmMotion(_OUT),
            left=ArmMotion(_OUT),
            period_s=None,
            arms="both, still",
            plane="sideways (frontal plane)",
            extent="arms out a little below shoulder height, palms down",
            signal="arms extended horizontally sideways, palms downward",
        ),
        GestureSpec(
            "land",
            right=ArmMotion(arm(plane=97, elevation=28, rotation=-60, elbow=22, pronation=0)),
            left=ArmMotion(arm(plane=97, elevation=28, rotation=-60, elbow=22, pronation=0)),
            period_s=None,
            arms="both, still",
            plane="down and forward, hands toward the midline",
            extent="hands low in front of the hips, close together or crossed",
            signal="arms placed down and crossed in front of the body",
        ),
        GestureSpec(
            "land_direction",
            right=ArmMotion(
                arm(plane=99, elevation=18, rotation=-30, elbow=30, pronation=0),
                arm(plane=98, elevation=83, rotation=-25, elbow=41, pronation=0),
            ),
            left=ArmMotion(
                arm(plane=99, elevation=18, rotation=-30, elbow=30, pronation=0),
                arm(plane=98, elevation=83, rotation=-25, elbow=41, pronation=0),
            ),
            period_s=(0.95, 1.5),
            dwell=(1.0, 1.5),
            arms="both, together",
            plane="forward (sagittal), hands converging",
            extent="from forearms forward-down to pointing ahead above shoulder height",
            signal="arms pointing forward in the landing direction",
        ),
        GestureSpec(
            "move_ahead",
            right=ArmMotion(
                arm(plane=45, elevation=16, elbow=10),
                arm(plane=65, elevation=105, rotation=20, elbow=70, pronation=-40),
            ),
            left=ArmMotion(
                arm(plane=45, elevation=16, elbow=10),
                arm(plane=65, elevation=105, rotation=20, elbow=70, pronation=-40),
            ),
            period_s=(1.05, 1.6),
            dwell=(1.0, 1.6),
            arms="both, together",
            plane="forward, hands shoulder-width apart",
            extent="from hanging to forearms up above shoulder height (beckoning)",
            signal="arms a little aside, palms facing backward, repeatedly moved upward-"
            "backward from shoulder height",
        ),
        GestureSpec(
            "move_downward",
            right=ArmMotion(
                arm(plane=5, elevation=82, rotation=0, elbow=15, pronation=0),
                arm(plane=0, elevation=15, rotation=-20, elbow=20, pronation=0),
            ),
            left=ArmMotion(
                arm(plane=5, elevation=82, rotation=0, elbow=15, pronation=0),
                arm(plane=0, elevation=15, rotation=-20, elbow=20, pronation=0),
            ),
            period_s=(0.95, 1.5),
            dwell=(1.0, 1.5),
            arms="both, together",
            plane="sideways (frontal plane)",
            extent="from shoulder height down to the hips, palms down",
            signal="arms extended horizontally sideways, palms down, beckoning downwards",
        ),
        GestureSpec(
            "move_upward",
            right=ArmMotion(
                arm(plane=5, elevation=80, rotation=80, elbow=20, pronation=-80),
                arm(plane=36, elevation=156, rotation=80, elbow=28, pronation=-80),
            ),
            left=ArmMotion(
                arm(plane=5, elevation=80, rotation=80, elbow=20, pronation=-80),
                arm(plane=36, elevation=156, rotation=80, elbow=28, pronation=-80),
            ),
            period_s=(1.1, 1.7),
            dwell=(1.0, 1.5),
            arms="both, together",
            plane="sideways (frontal plane)",
            extent="from shoulder height to nearly vertical, palms up",
            signal="arms extended horizontally sideways, palms up, beckoning upwards",
        ),
        GestureSpec(
            "move_to_left",
            right=ArmMotion(
                arm(plane=0, elevation=70, rotation=67, elbow=20, pronation=0),
                arm(plane=31, elevation=74, rotation=15, elbow=133, pronation=0),
            ),
            left=ArmMotion(_OUT),
            period_s=(0.95, 1.5),
            dwell=(1.0, 1.5),
            arms="left arm held out; right arm swings",
            plane="frontal, over the head",
            extent="the right forearm sweeps from out sideways to over the head, toward the "
            "held arm",
            signal="one arm extended horizontally sideways in the direction of movement, the "
            "other swung over the head in the same direction",
        ),
        GestureSpec(
            "move_to_right",
            right=ArmMotion(_OUT),
            left=ArmMotion(
                arm(plane=0, elevation=70, rotation=67, elbow=20, pronation=0),
                arm(plane=31, elevation=74, rotation=15, elbow=133, pronation=0),
            ),
            period_s=(1.05, 1.6),
            dwell=(1.0, 1.5),
            arms="right arm held out; left arm swings",
            plane="frontal, over the head",
            extent="mirror of move_to_left",
            signal="as move_to_left, to the other side",
        ),
        GestureSpec(
            "slow_down",
            right=ArmMotion(
                arm(plane=15, elevation=13, elbow=6, pronation=60),
                arm(plane=30, elevation=30, rotation=0, elbow=130, pronation=80),
            ),
            left=ArmMotion(
                arm(plane=15, elevation=13, elbow=6, pronation=60),
                arm(plane=30, elevation=30, rotation=0, elbow=130, pronation=80),
            ),
            period_s=(1.05, 1.6),
            dwell=(0.7, 1.0),
            arms="both, together",
            plane="forward, elbows at the sides",
            extent="forearms from hanging to up in front, hands to shoulder height, palms down",
            signal="arms down with palms toward the ground, moved up and down several times",
        ),
        GestureSpec(
            "wave_off",
            right=ArmMotion(
                arm(plane=13, elevation=102, rotation=70, elbow=16),
                arm(plane=96, elevation=123, rotation=-70, elbow=66),
            ),
            left=ArmMotion(
                arm(plane=13, elevation=102, rotation=70, elbow=16),
                arm(plane=86, elevation=120, rotation=-70, elbow=66),
            ),
            period_s=(1.35, 2.0),
            dwell=(1.0, 1.5),
            arms="both, together",
            plane="above the head",
            extent="from arms out above shoulder height to the forearms crossed above the head",
            signal="waving of arms over the head (arms repeatedly crossed above the head)",
        ),
    )
}

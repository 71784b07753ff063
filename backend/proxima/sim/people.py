"""The people of a simulated scene: the operator performing a script of gestures, and
bystanders who do not command the drones (standing, moving their arms at random, walking
past, or signalling to someone else).

Each person is a `synth` body whose 33 landmarks are computed in the scene's world (NED
metres) for every frame of the scene at once, when the scene is made: a stream only
looks them up by frame index and projects them through its camera.

Scripts are `GESTURE:SECONDS` steps separated by commas (`hover:4,have_command:4`;
`idle` for a still stance): one performance per script, played by `synth.motion.perform`,
starting and ending in an idle stance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from proxima.synth.anthropometry import BodyShape, sample_body
from proxima.synth.body import Placement, Posture, Stance, body_landmarks
from proxima.synth.gestures import IDLE
from proxima.synth.motion import (
    IDLE_LABEL,
    GestureDraw,
    Performance,
    draw_gesture,
    perform,
    smooth_noise,
)
from proxima.types import GESTURES

Behaviour = Literal["operator", "stand", "arms", "walk", "gestures"]
BEHAVIOURS: tuple[str, ...] = ("stand", "arms", "walk", "gestures")
LEAD_S = 1.0  # idle before the script's first gesture
TAIL_S = 1.5  # idle after its last
STEP_HZ = 1.8  # walking cadence: steps a second
PAUSE_S = 1.2  # a walker stands and turns this long at each end of its path


class ScriptError(ValueError):
    """A script that cannot be performed; the message names the step."""


def parse_script(text: str | Sequence[Sequence[object]]) -> list[tuple[str, float]]:
    """`GESTURE:SECONDS,...` (or a list of [gesture, seconds] pairs) -> steps.

    Raises:
        ScriptError: an unknown gesture, a duration that is not a positive number, or
            an empty script.
    """
    if isinstance(text, str):
        pairs: list[Sequence[object]] = []
        for part in (p.strip() for p in text.split(",")):
            if not part:
                continue
            gesture, sep, duration = part.partition(":")
            if not sep:
                raise ScriptError(f"script step {part!r}: expected GESTURE:SECONDS")
            pairs.append((gesture.strip(), duration.strip()))
    else:
        pairs = list(text)
    steps: list[tuple[str, float]] = []
    for pair in pairs:
        if len(pair) != 2:
            raise ScriptError(f"script step {pair!r}: expected [gesture, seconds]")
        name, seconds = str(pair[0]), pair[1]
        if name != "idle" and name not in GESTURES:
            raise ScriptError(
                f"script step {name!r}: not a gesture; choose idle or one of {', '.join(GESTURES)}"
            )
        try:
            s = float(seconds)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ScriptError(
                f"script step {name}: {seconds!r} is not a number of seconds"
            ) from None
        if not (math.isfinite(s) and 0 < s <= 600):
            raise ScriptError(f"script step {name}: {seconds!r} s must lie in (0, 600]")
        steps.append((name, s))
    if not steps:
        raise ScriptError("the script has no steps")
    return steps


def script_text(steps: Sequence[tuple[str, float]]) -> str:
    return ",".join(f"{g}:{s:g}" for g, s in steps)


@dataclass
class Person:
    """One person of the scene: `world` (T, 33, 3) landmarks per frame (NED metres),
    `labels` (T,) the gesture each frame belongs to ("" for none; only the operator's
    mean anything), `segments` the operator's script steps as frame spans."""

    name: str
    behaviour: Behaviour
    body: BodyShape
    world: np.ndarray
    labels: np.ndarray
    segments: list[tuple[str, int, int, int]] = field(default_factory=list)

    @property
    def operator(self) -> bool:
        return self.behaviour == "operator"

    def chest(self, k: int) -> np.ndarray:
        """World point (3,) between the shoulders and hips at frame k."""
        return self.world[k % len(self.world)][[11, 12, 23, 24]].mean(axis=0)


def _place(
    points: np.ndarray, north: np.ndarray, east: np.ndarray, heading_deg: np.ndarray
) -> np.ndarray:
    """Body-frame points (T, 33, 3) (x forward, y left, z up) -> NED, with a placement
    per frame (`Placement.to_world`, vectorised over time)."""
    h = np.deg2rad(heading_deg)[:, None]
    c, s = np.cos(h), np.sin(h)
    fx, fy, fz = points[..., 0], -points[..., 1], -points[..., 2]
    out = np.stack([c * fx - s * fy + north[:, None], s * fx + c * fy + east[:, None], fz], -1)
    return out


def _perform_steps(
    steps: Sequence[tuple[str, float]],
    body: BodyShape,
    rng: np.random.Generator,
    fps: float,
    lead_s: float = LEAD_S,
    tail_s: float = TAIL_S,
) -> Performance:
    draws = [draw_gesture(IDLE_LABEL, rng, duration_s=lead_s)]
    for gesture, seconds in steps:
        g = IDLE_LABEL if gesture == "idle" else gesture
        draws.append(draw_gesture(g, rng, body.handedness, duration_s=seconds))
    draws.append(draw_gesture(IDLE_LABEL, rng, duration_s=tail_s))
    return perform(draws, rng, fps)


def _fit(values: np.ndarray, frames: int) -> np.ndarray:
    """`values` (n, ...) cut or padded (holding the last) to `frames` rows."""
    if len(values) >= frames:
        return values[:frames]
    pad = np.repeat(values[-1:], frames - len(values), axis=0)
    return np.concatenate([values, pad])


def _fit_posture(p: Posture, frames: int) -> Posture:
    return Posture(
        _fit(p.right_arm, frames),
        _fit(p.left_arm, frames),
        _fit(p.pelvis, frames),
        _fit(p.trunk, frames),
        _fit(p.head, frames),
        _fit(p.knees, frames),
    )


def operator(
    steps: Sequence[tuple[str, float]],
    placement: Placement,
    rng: np.random.Generator,
    fps: float,
    body: BodyShape | None = None,
) -> Person:
    """The operator: performs `steps` (after a short idle stance, ending in one) where
    `placement` puts them, facing its heading."""
    body = body or sample_body(rng, handedness="right")
    perf = _perform_steps(steps, body, rng, fps)
    world = placement.to_world(body_landmarks(body, perf.posture, Stance()))
    return Person("operator", "operator", body, world, perf.labels, list(perf.segments))


def _random_arms(rng: np.random.Generator, seconds: float) -> list[GestureDraw]:
    """Idle steps with random arm poses: the arms move from one to the next (0.35-0.7 s)
    and hold it (0.4-1.6 s), like someone talking, stretching or pointing."""
    draws: list[GestureDraw] = []
    total = 0.0
    while total < seconds:
        pose: list[tuple[float, ...]] = []
        for _ in range(2):
            pose.append(
                (
                    float(rng.uniform(-30, 120)),  # plane of elevation
                    float(rng.uniform(0, 150)),  # elevation
                    float(rng.uniform(-40, 60)),  # axial rotation
                    float(rng.uniform(0, 120)),  # elbow
                    float(rng.uniform(-60, 60)),  # pronation
                    0.0,
                    0.0,
                )
            )
        if rng.random() < 0.4:  # one arm often stays down
            pose[int(rng.integers(2))] = tuple(float(v) for v in IDLE)
        hold = float(rng.uniform(0.4, 1.6))
        entry = float(rng.uniform(0.35, 0.7))
        draws.append(GestureDraw("", hold, entry, pose[0], pose[1]))
        total += hold + entry
    return draws


def bystander(
    name: str,
    behaviour: Behaviour,
    placement: Placement,
    frames: int,
    rng: np.random.Generator,
    fps: float,
    *,
    to: tuple[float, float] | None = None,
    speed_m_s: float = 1.2,
    steps: Sequence[tuple[str, float]] = (),
) -> Person:
    """A person who is not the operator, for `frames` frames: `stand` (idle, swaying),
    `arms` (random arm poses), `gestures` (performs `steps`, e.g. signalling to another
    drone), or `walk` (back and forth between `placement` and `to` at `speed_m_s`).

    Raises:
        ValueError: an unknown behaviour, `walk` without `to`, `gestures` without steps.
    """
    body = sample_body(rng)
    seconds = frames / fps
    labels = np.full(frames, "", dtype=object)
    if behaviour == "stand":
        perf = perform([draw_gesture(IDLE_LABEL, rng, duration_s=seconds)], rng, fps)
    elif behaviour == "arms":
        perf = perform(_random_arms(rng, seconds), rng, fps)
    elif behaviour == "gestures":
        if not steps:
            raise ValueError(f"bystander {name}: `gestures` needs a script")
        perf = _perform_steps(steps, body, rng, fps)
        labels = _fit(np.asarray(perf.labels, dtype=object), frames)
    elif behaviour == "walk":
        if to is None:
            raise ValueError(f"bystander {name}: `walk` needs `to` (the path's other end)")
        world = _walk(body, placement, to, speed_m_s, frames, fps, rng)
        return Person(name, behaviour, body, world, labels)
    else:
        raise ValueError(f"bystander {name}: unknown behaviour {behaviour!r}; choose {BEHAVIOURS}")
    posture = _fit_posture(perf.posture, frames)
    world = placement.to_world(body_landmarks(body, posture, Stance()))
    return Person(name, behaviour, body, world, labels)


def _two_bone(hip: np.ndarray, ankle: np.ndarray, thigh: float, shank: float) -> np.ndarray:
    """Knees (T, 3) between hips and ankles (body frame), bending forward (+x)."""
    d_vec = ankle - hip
    d = np.clip(np.linalg.norm(d_vec, axis=-1, keepdims=True), 1e-6, thigh + shank - 1e-6)
    e = d_vec / np.maximum(np.linalg.norm(d_vec, axis=-1, keepdims=True), 1e-9)
    a = (thigh**2 - shank**2 + d**2) / (2 * d)
    h = np.sqrt(np.maximum(thigh**2 - a**2, 0.0))
    fwd = np.array([1.0, 0.0, 0.0])
    n = fwd - np.sum(fwd * e, axis=-1, keepdims=True) * e
    n = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-9)
    return hip + a * e + h * n


def _walk(
    body: BodyShape,
    start: Placement,
    to: tuple[float, float],
    speed: float,
    frames: int,
    fps: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """World landmarks (T, 33, 3) of a person walking back and forth between `start`
    and `to`, standing and turning for `PAUSE_S` at each end. The gait: feet swinging
    sinusoidally by half a step about the hips, the swinging foot lifted, knees by
    two-bone inverse kinematics, arms swinging against the legs."""
    a = np.array([start.north, start.east])
    b = np.asarray(to, np.float64)
    length = float(np.linalg.norm(b - a))
    if length < 0.5:
        raise ValueError(f"a walk needs a path of at least 0.5 m, got {length:.2f} m")
    speed = float(np.clip(speed, 0.3, 2.5))
    walk_s = length / speed
    cycle = 2 * (walk_s + PAUSE_S)
    t = (np.arange(frames) / fps + float(rng.uniform(0, cycle))) % cycle
    h_ab = math.degrees(math.atan2(b[1] - a[1], b[0] - a[0]))
    # Where along the path (0..1), the heading, and whether walking (1) or standing (0).
    s = np.empty(frames)
    heading = np.empty(frames)
    moving = np.zeros(frames)
    for i, ti in enumerate(t):
        if ti < walk_s:
            s[i], heading[i], moving[i] = ti / walk_s, h_ab, 1.0
        elif ti < walk_s + PAUSE_S:
            u = (ti - walk_s) / PAUSE_S
            s[i], heading[i] = 1.0, h_ab + 180.0 * u * u * (3 - 2 * u)
        elif ti < 2 * walk_s + PAUSE_S:
            s[i], heading[i], moving[i] = 1.0 - (ti - walk_s - PAUSE_S) / walk_s, h_ab + 180, 1.0
        else:
            u = (ti - 2 * walk_s - PAUSE_S) / PAUSE_S
            s[i], heading[i] = 0.0, h_ab + 180.0 + 180.0 * u * u * (3 - 2 * u)
    # Ramp the gait in and out over 0.3 s around the pauses.
    k = max(int(0.3 * fps), 1)
    amp = np.convolve(np.pad(moving, k, mode="edge"), np.ones(2 * k + 1) / (2 * k + 1), "same")
    amp = amp[k:-k]
    step_len = speed / STEP_HZ
    phase = 2 * np.pi * np.cumsum(amp * STEP_HZ / 2 / fps)  # one stride = two steps
    sw = np.sin(phase)

    arm_r = np.tile(np.asarray(IDLE, np.float64), (frames, 1))
    arm_l = arm_r.copy()
    for arm, sign in ((arm_r, 1.0), (arm_l, -1.0)):
        swing = sign * sw * amp
        arm[:, 0] = np.where(swing >= 0, 90.0, -90.0)  # forward or backward plane
        arm[:, 1] = 18.0 * np.abs(swing)
        arm[:, 3] = 15.0 + 10.0 * np.maximum(swing, 0)
    z3 = np.zeros((frames, 3))
    trunk = smooth_noise(rng, frames, fps, 0.25, 3) * [0.8, 0.6, 1.5]
    head = smooth_noise(rng, frames, fps, 0.3, 3) * [3.0, 2.0, 1.0]
    posture = Posture(arm_r, arm_l, z3, trunk, head, np.full(frames, 4.0))
    pts = body_landmarks(body, posture, Stance(foot_width=0.16, toe_out_deg=6.0))
    # Feet: the left forward when sin > 0; the foot swinging forward is lifted.
    lift = 0.07 * body.stature / 1.75
    for feet, ankle, hip, sign in (((27, 29, 31), 27, 23, 1.0), ((28, 30, 32), 28, 24, -1.0)):
        thigh = float(np.linalg.norm(pts[0, hip] - pts[0, hip + 2]))  # before the feet move
        shank = float(np.linalg.norm(pts[0, hip + 2] - pts[0, ankle]))
        x = sign * sw * amp * step_len / 2
        up = lift * np.maximum(sign * np.cos(phase), 0.0) * amp
        for j in feet:
            pts[:, j, 0] += x
            pts[:, j, 2] += up
        pts[:, hip + 2] = _two_bone(pts[:, hip], pts[:, ankle], thigh, shank)
    where = a[None] + s[:, None] * (b - a)[None]
    return _place(pts, where[:, 0], where[:, 1], heading)

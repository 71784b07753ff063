"""The arm's joint angles, their limits, and the same angles measured back from landmarks.

An arm's pose is seven angles in degrees (`ARM_DOF`), in the shoulder's "globe" system
(the ISB recommendation for the humerus, Wu et al. 2005):
- `plane`: plane of elevation, 0 = sideways (abduction), 90 = forward (flexion),
  -90 = backward (extension), above 90 = across the front of the body;
- `elevation`: angle of the upper arm from hanging straight down (0) to straight up (180);
- `rotation`: humeral axial rotation, external (outward) positive;
- `elbow`: flexion, 0 = straight;
- `pronation`: forearm pronation, supination negative (0 = thumb up with the elbow bent
  at the side);
- `wrist_dev`: radial (toward the thumb) positive, ulnar negative;
- `wrist_flex`: flexion (toward the palm) positive, extension negative.

Limits are the normal active ranges of the American Academy of Orthopaedic Surgeons
(AAOS), as tabulated in C. C. Norkin & D. J. White, *Measurement of Joint Motion*, F. A.
Davis, Table A.1: shoulder flexion 180, extension 60, abduction 180, medial rotation 70,
lateral rotation 90; elbow flexion 150 (extension 0); pronation and supination 80; wrist
flexion 80, extension 70, radial deviation 20, ulnar deviation 30. The table gives single
planes only; between them the elevation limit here rises linearly from extension's 60
degrees (plane -90) to 180 at plane -30 (an assumption), and planes across the body end
at 135 (horizontal adduction).

`arm_angles` measures plane, elevation, rotation and elbow from landmark positions alone
(the torso frame from the shoulder and hip landmarks), so a test can check any generated
pose against the limits without trusting the generator's own bookkeeping.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ARM_DOF = ("plane", "elevation", "rotation", "elbow", "pronation", "wrist_dev", "wrist_flex")
PLANE, ELEVATION, ROTATION, ELBOW, PRONATION, WRIST_DEV, WRIST_FLEX = range(7)


@dataclass(frozen=True)
class ArmLimits:
    """Ranges in degrees (see the module docstring for their source)."""

    plane: tuple[float, float] = (-90.0, 135.0)
    elevation: tuple[float, float] = (0.0, 180.0)
    rotation: tuple[float, float] = (-70.0, 90.0)
    elbow: tuple[float, float] = (0.0, 150.0)
    pronation: tuple[float, float] = (-80.0, 80.0)
    wrist_dev: tuple[float, float] = (-30.0, 20.0)
    wrist_flex: tuple[float, float] = (-70.0, 80.0)
    extension_elevation: float = 60.0  # largest elevation straight backward (plane -90)
    full_elevation_plane: float = -30.0  # from this plane forward, elevation up to 180

    def ranges(self) -> np.ndarray:
        """(7, 2) low / high per degree of freedom, in `ARM_DOF` order."""
        return np.array([getattr(self, name) for name in ARM_DOF], dtype=np.float64)

    def max_elevation(self, plane: np.ndarray) -> np.ndarray:
        """Largest elevation allowed in a plane of elevation (degrees)."""
        lo = self.plane[0]
        frac = np.clip((np.asarray(plane) - lo) / (self.full_elevation_plane - lo), 0.0, 1.0)
        return self.extension_elevation + frac * (self.elevation[1] - self.extension_elevation)


ARM_LIMITS = ArmLimits()


def clamp_arm(angles: np.ndarray, limits: ArmLimits = ARM_LIMITS) -> np.ndarray:
    """Angles (..., 7) brought inside the limits: each range, then the elevation cap of
    the plane."""
    r = limits.ranges()
    out = np.clip(np.asarray(angles, np.float64), r[:, 0], r[:, 1])
    out[..., ELEVATION] = np.minimum(out[..., ELEVATION], limits.max_elevation(out[..., PLANE]))
    return out


def _rotate(v: np.ndarray, axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues' rotation of vectors v (..., 3) about unit axes (..., 3) by angles (...)."""
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    dot = np.sum(axis * v, axis=-1, keepdims=True)
    return v * c + np.cross(axis, v) * s + axis * dot * (1 - c)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def upper_arm_axes(plane: np.ndarray, elevation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Upper-arm direction u and the forearm's bend direction b at zero axial rotation,
    both (..., 3) in the arm's frame (forward, outward, up), for angles in degrees.

    b is where the forearm goes when the elbow bends: forward for an arm hanging at the
    side or held out sideways, upward for an arm raised forward."""
    p, t = np.deg2rad(plane), np.deg2rad(elevation)
    fwd = np.array([1.0, 0.0, 0.0])
    down = np.array([0.0, 0.0, -1.0])
    direction = np.stack([np.sin(p), np.cos(p), np.zeros_like(p)], axis=-1)  # in the plane
    u = np.sin(t)[..., None] * direction + np.cos(t)[..., None] * down
    axis = _unit(np.cross(np.broadcast_to(down, direction.shape), direction))
    b = _rotate(np.broadcast_to(fwd, direction.shape), axis, t)
    return u, b


def arm_directions(angles: np.ndarray) -> dict[str, np.ndarray]:
    """Unit vectors (..., 3) of one arm in its frame (forward, outward, up): upper arm `u`,
    forearm `f`, hand axis `h`, thumb side `t`, palm normal `p` (the way the palm faces).

    The frame (forward, outward, up) is right-handed for the left arm; the right arm uses
    the same numbers and is mirrored into the world (outward = the body's right)."""
    a = np.deg2rad(np.asarray(angles, np.float64))
    u, b = upper_arm_axes(np.rad2deg(a[..., PLANE]), np.rad2deg(a[..., ELEVATION]))
    b = _rotate(b, u, -a[..., ROTATION])  # external rotation turns b from forward to up
    e = a[..., ELBOW][..., None]
    f = np.cos(e) * u + np.sin(e) * b
    palm = _unit(np.cross(u, b))  # medial with the arm at the side: palm toward the thigh
    thumb = _unit(np.cross(palm, f))
    thumb = _rotate(thumb, f, a[..., PRONATION])
    palm = _rotate(palm, f, a[..., PRONATION])
    d, k = a[..., WRIST_DEV][..., None], a[..., WRIST_FLEX][..., None]
    h = np.cos(d) * f + np.sin(d) * thumb
    thumb = -np.sin(d) * f + np.cos(d) * thumb
    h2 = np.cos(k) * h + np.sin(k) * palm
    palm = -np.sin(k) * h + np.cos(k) * palm
    return {"u": u, "f": f, "h": h2, "t": thumb, "p": palm}


def torso_frame(landmarks: np.ndarray) -> np.ndarray:
    """(..., 33, 3) landmark positions (any right-handed metric frame) -> (..., 3, 3) rows
    forward, left, up of the torso: up from the hips' to the shoulders' midpoint, left
    along the shoulder line."""
    sh = (landmarks[..., 11, :] + landmarks[..., 12, :]) / 2
    hp = (landmarks[..., 23, :] + landmarks[..., 24, :]) / 2
    up = _unit(sh - hp)
    across = landmarks[..., 11, :] - landmarks[..., 12, :]
    left = _unit(across - np.sum(across * up, axis=-1, keepdims=True) * up)
    fwd = np.cross(left, up)
    return np.stack([fwd, left, up], axis=-2)


def arm_angles(landmarks: np.ndarray, side: str) -> dict[str, np.ndarray]:
    """Plane, elevation, axial rotation and elbow flexion (degrees, arrays (...,)) of one
    arm ("left" or "right"), measured from 3D landmark positions (..., 33, 3).

    Rotation is NaN where it is undefined: elbow nearly straight (under 15 degrees) or the
    arm nearly vertical (elevation under 10 or over 170)."""
    s, e, w = (11, 13, 15) if side == "left" else (12, 14, 16)
    frame = torso_frame(landmarks)
    if side == "right":
        frame = frame * np.array([1.0, -1.0, 1.0])[:, None]  # outward = the body's right
    u = _unit(np.einsum("...ij,...j->...i", frame, landmarks[..., e, :] - landmarks[..., s, :]))
    f = _unit(np.einsum("...ij,...j->...i", frame, landmarks[..., w, :] - landmarks[..., e, :]))
    elevation = np.rad2deg(np.arccos(np.clip(-u[..., 2], -1, 1)))
    plane = np.rad2deg(np.arctan2(u[..., 0], u[..., 1]))
    elbow = np.rad2deg(np.arccos(np.clip(np.sum(u * f, axis=-1), -1, 1)))
    _, b0 = upper_arm_axes(plane, elevation)
    bent = _unit(f - np.sum(f * u, axis=-1, keepdims=True) * u)
    rotation = -np.rad2deg(
        np.arctan2(np.sum(np.cross(b0, bent) * u, axis=-1), np.sum(b0 * bent, axis=-1))
    )
    undefined = (elbow < 15) | (elevation < 10) | (elevation > 170)
    rotation = np.where(undefined, np.nan, rotation)
    return {"plane": plane, "elevation": elevation, "rotation": rotation, "elbow": elbow}


def limit_violations(
    landmarks: np.ndarray, limits: ArmLimits = ARM_LIMITS, tol: float = 0.5
) -> list[str]:
    """Every shoulder or elbow angle outside the limits, measured from landmarks
    (T, 33, 3); one line per arm and joint that breaks them (empty: none does).

    The plane of elevation is only checked where it is defined (elevation over 10)."""
    problems: list[str] = []
    for side in ("left", "right"):
        a = arm_angles(landmarks, side)
        elev, plane = a["elevation"], a["plane"]
        defined = elev > 10
        checks = {
            "elbow flexion": (a["elbow"] < limits.elbow[0] - tol)
            | (a["elbow"] > limits.elbow[1] + tol),
            "plane of elevation": defined
            & ((plane < limits.plane[0] - tol) | (plane > limits.plane[1] + tol)),
            "elevation": elev > limits.max_elevation(np.clip(plane, *limits.plane)) + tol,
            "axial rotation": (a["rotation"] < limits.rotation[0] - tol)
            | (a["rotation"] > limits.rotation[1] + tol),
        }
        for name, bad in checks.items():
            if np.any(bad):
                i = int(np.flatnonzero(bad)[0])
                values = {k: round(float(v[i]), 1) for k, v in a.items()}
                problems.append(f"{side} {name}: {int(np.sum(bad))} frame(s), first {i}: {values}")
    return problems

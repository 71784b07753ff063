"""Pick the operator among the people in view, follow them, smooth their landmarks, and
decide whether they are "visible" for the drone-priority handover.

Selection (`OperatorTracker`):
- Before arming, the operator is the most central and largest person: score =
  bounding-box area (fraction of the image) x (1 - distance of the body centre from the
  image centre / 0.71). The current choice is kept from frame to frame and only given up
  for someone scoring `switch_margin` times higher, so two similar people do not make
  it flicker.
- When the engine recognises the arming gesture it calls `lock_current()`: from then on
  only that person is followed, frame to frame, as the detection whose body centre
  (mean of shoulders and hips) is nearest to the last one, within a gate that widens
  with the time since they were last seen. Nobody inside the gate means "operator not
  found" (None), never a switch to someone else; `unlock()` (on disarm) ends the lock.

Visibility (`operator_visible`, `operator_sight`): see their docstrings. Feet count
because the paper's handover happens when the main drone's camera loses the operator's
feet.
"""

from __future__ import annotations

import numpy as np

from proxima.pose.one_euro import LIVE_ONE_EURO, OneEuroFilter
from proxima.types import Pose, Sight

SHOULDERS = (11, 12)
HIPS = (23, 24)
FEET = (27, 28, 29, 30, 31, 32)  # ankles, heels, foot indices (left, right)
_TORSO = list(SHOULDERS + HIPS)
_MAX_CENTRE_DIST = float(np.hypot(0.5, 0.5))


def operator_visible(
    pose: Pose | None,
    threshold: float = 0.5,
    min_fraction: float = 0.6,
    min_feet: int = 3,
) -> bool:
    """True when the operator counts as seen by this camera.

    Definition: at least `min_fraction` of the 33 landmarks have visibility >=
    `threshold`, AND at least `min_feet` of the 6 foot landmarks (27..32: ankles, heels,
    foot indices) have visibility >= `threshold`. With the defaults that is 20 of 33
    landmarks and e.g. one whole foot. In the LASER data, frames failing the feet part
    are the ones whose feet lie below the image edge (y > 1), so the test catches a
    camera that has lost the operator's feet. No pose (None) is not visible.
    """
    return operator_sight(pose, threshold, min_fraction, min_feet) == Sight.FULL


def operator_sight(
    pose: Pose | None, threshold: float = 0.5, min_fraction: float = 0.6, min_feet: int = 3
) -> Sight:
    """How well a camera sees the operator: FULL when `operator_visible` holds, PARTIAL
    when enough landmarks are seen (the same `min_fraction`) but the feet are not, NONE
    otherwise (no pose, or too few landmarks to read a gesture)."""
    if pose is None:
        return Sight.NONE
    seen = pose.visibility >= threshold
    if seen.mean() < min_fraction:
        return Sight.NONE
    return Sight.FULL if int(seen[list(FEET)].sum()) >= min_feet else Sight.PARTIAL


def body_centre(pose: Pose) -> np.ndarray:
    """Mean (x, y) of the shoulders and hips, normalised image coordinates."""
    return pose.xyz[_TORSO, :2].mean(axis=0).astype(np.float64)


def body_area(pose: Pose, threshold: float = 0.5) -> float:
    """Bounding-box area of the landmarks seen (visibility >= threshold), as a fraction
    of the image (all landmarks if fewer than 4 are seen), clipped to the image."""
    xy = pose.xyz[:, :2]
    seen = pose.visibility >= threshold
    if seen.sum() >= 4:
        xy = xy[seen]
    lo = np.clip(xy.min(axis=0), 0.0, 1.0)
    hi = np.clip(xy.max(axis=0), 0.0, 1.0)
    return float(np.prod(hi - lo))


def selection_score(pose: Pose) -> float:
    """Larger and more central scores higher (see the module docstring)."""
    off_centre = float(np.hypot(*(body_centre(pose) - 0.5))) / _MAX_CENTRE_DIST
    return body_area(pose) * max(0.0, 1.0 - off_centre)


class OperatorTracker:
    """Chooses and follows the operator, returning their smoothed pose each frame.

    `update(poses, t)` returns the operator's pose (landmarks smoothed with a One Euro
    filter, visibility as detected) or None when the operator is not found in this
    frame. `track_id` changes whenever a different person becomes the operator, so a
    consumer can restart anything built from the previous person's frames.
    """

    def __init__(
        self,
        *,
        gate: float = 0.1,
        gate_speed: float = 0.5,
        max_gate: float = 0.3,
        switch_margin: float = 1.25,
        reset_after_s: float = 0.5,
        smooth: bool = True,
        min_cutoff: float = LIVE_ONE_EURO.min_cutoff,
        beta: float = LIVE_ONE_EURO.beta,
        d_cutoff: float = LIVE_ONE_EURO.d_cutoff,
    ) -> None:
        self.gate = gate  # normalised distance allowed between consecutive frames
        self.gate_speed = gate_speed  # extra distance per second unseen
        self.max_gate = max_gate
        self.switch_margin = switch_margin
        self.reset_after_s = reset_after_s
        self._filter = OneEuroFilter(min_cutoff, beta, d_cutoff) if smooth else None
        self._locked = False
        self._centre: np.ndarray | None = None
        self._last_seen: float | None = None
        self.track_id = 0

    @property
    def locked(self) -> bool:
        """True while following the person who armed control."""
        return self._locked

    def lock_current(self) -> bool:
        """Lock on the person currently followed (call when `have_command` is
        recognised). Returns False when nobody is being followed (nothing locked)."""
        if self._centre is None:
            return False
        self._locked = True
        return True

    def unlock(self) -> None:
        """Stop following only the armed operator (call on disarm)."""
        self._locked = False

    def reset(self) -> None:
        """Forget the operator entirely (new stream)."""
        self._locked = False
        self._centre = None
        self._last_seen = None
        if self._filter is not None:
            self._filter.reset()

    def _nearest_within_gate(self, poses: list[Pose], t: float) -> int | None:
        if self._centre is None or self._last_seen is None or not poses:
            return None
        unseen = max(t - self._last_seen, 0.0)
        gate = min(self.gate + self.gate_speed * unseen, self.max_gate)
        dists = [float(np.hypot(*(body_centre(p) - self._centre))) for p in poses]
        k = int(np.argmin(dists))
        return k if dists[k] <= gate else None

    def update(self, poses: list[Pose], t: float) -> Pose | None:
        """Choose the operator among `poses` (all people found at stream time `t`)."""
        same = self._nearest_within_gate(poses, t)
        if self._locked:
            chosen = same
        elif not poses:
            chosen = None
        else:
            scores = [selection_score(p) for p in poses]
            best = int(np.argmax(scores))
            if same is None or scores[best] > self.switch_margin * scores[same]:
                chosen = best
            else:
                chosen = same
        if chosen is None:
            return None
        pose = poses[chosen]
        gap = t - self._last_seen if self._last_seen is not None else None
        new_person = chosen != same
        if new_person:
            self.track_id += 1
        if self._filter is not None and (new_person or gap is None or gap > self.reset_after_s):
            self._filter.reset()
        self._centre = body_centre(pose)
        self._last_seen = t
        if self._filter is None:
            return pose
        xyz = self._filter(pose.xyz, t).astype(np.float32)
        return Pose(t=pose.t, xyz=xyz, visibility=pose.visibility, image_size=pose.image_size)

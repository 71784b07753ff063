"""Operator selection, tracking, smoothing and the visibility test, on real landmarks
from the LASER dataset and on real MediaPipe output for a two-person image."""

from __future__ import annotations

from pathlib import Path

import cv2
import matplotlib
import numpy as np
import pytest

from proxima.ingest import read_landmark_csv
from proxima.pose import (
    OneEuroFilter,
    OperatorTracker,
    PoseEstimator,
    body_centre,
    operator_sight,
    operator_visible,
    selection_score,
)
from proxima.types import Pose, Sight

skimage_data = pytest.importorskip("skimage.data")

LASER = Path(__file__).resolve().parents[2].parent / "shared" / "datasets" / "laser-uav-gesture"


@pytest.fixture(scope="module")
def clip():
    return read_landmark_csv(LASER / "DJI_0158_move_ahead_f.MP4.csv")


def _pose(xyz: np.ndarray, vis: np.ndarray, t: float, dx: float = 0.0, scale: float = 1.0) -> Pose:
    """A real pose moved by `dx` and scaled about its body centre (a second person)."""
    out = xyz.copy()
    centre = out[[11, 12, 23, 24], :2].mean(axis=0)
    out[:, :2] = (out[:, :2] - centre) * scale + centre
    out[:, 0] += dx
    return Pose(t=t, xyz=out, visibility=vis.copy())


def test_visibility_test_requires_feet() -> None:
    slow = read_landmark_csv(LASER / "DJI_0173_slow_down_f.MP4.csv")
    results = np.array(
        [operator_visible(Pose(0.0, x, v)) for x, v in zip(slow.xyz, slow.visibility, strict=True)]
    )
    ankle_y = slow.xyz[:, [27, 28], 1].min(axis=1)
    # Frames judged not visible are those whose feet left the bottom of the image.
    assert 0.1 < results.mean() < 0.9
    assert np.median(ankle_y[~results]) > 1.0 > np.median(ankle_y[results])
    full = read_landmark_csv(LASER / "DJI_0149_hover_f.MP4.csv")
    assert all(
        operator_visible(Pose(0.0, x, v)) for x, v in zip(full.xyz, full.visibility, strict=True)
    )
    # Feet alone are not enough, and neither is the body without feet.
    x, v = full.xyz[0], full.visibility[0].copy()
    v_no_feet = v.copy()
    v_no_feet[27:33] = 0.1
    assert not operator_visible(Pose(0.0, x, v_no_feet))
    v_feet_only = np.full(33, 0.1, np.float32)
    v_feet_only[27:33] = 0.9
    assert not operator_visible(Pose(0.0, x, v_feet_only))
    assert not operator_visible(None)
    # The levels the arbiter and the drone watchdog share: the body without its feet is
    # still enough to read gestures (PARTIAL); feet alone or nothing are not (NONE).
    assert operator_sight(Pose(0.0, x, v)) == Sight.FULL
    assert operator_sight(Pose(0.0, x, v_no_feet)) == Sight.PARTIAL
    assert operator_sight(Pose(0.0, x, v_feet_only)) == Sight.NONE
    assert operator_sight(None) == Sight.NONE
    frames = zip(slow.xyz, slow.visibility, strict=True)
    sights = [operator_sight(Pose(0.0, x, v)) for x, v in frames]
    assert [s == Sight.FULL for s in sights] == results.tolist()
    # slow_down's feet leave the image, the body nearly never does.
    assert sights.count(Sight.NONE) < 0.02 * len(sights)


def test_one_euro_filter_smooths_jitter_and_follows_motion() -> None:
    rng = np.random.default_rng(0)
    t = np.arange(300) / 30.0
    still = 0.5 + rng.normal(0, 0.01, size=(300, 2))
    f = OneEuroFilter()
    out = np.array([f(x, ti) for x, ti in zip(still, t, strict=True)])
    assert out[30:].std() < 0.65 * still[30:].std()  # jitter at rest reduced
    # A fast move (1 image width a second) is followed with little lag.
    ramp = (t * 1.0)[:, None] + rng.normal(0, 0.002, size=(300, 1))
    f.reset()
    out = np.array([f(x, ti) for x, ti in zip(ramp, t, strict=True)])
    assert np.abs(out[60:, 0] - t[60:]).max() < 0.05
    # A repeated timestamp returns the last output; a shape change needs a reset.
    assert f(np.array([9.0]), t[-1]) == pytest.approx(out[-1])
    with pytest.raises(ValueError, match="reset"):
        f(np.zeros(3), 100.0)
    assert f.__class__(min_cutoff=1.0)(np.ones(2), 0.0).tolist() == [1.0, 1.0]


def test_tracker_smooths_a_real_noisy_stream(clip) -> None:
    rng = np.random.default_rng(1)
    tracker = OperatorTracker()
    raw_err, smooth_err = [], []
    for k in range(200):
        t = k / 30
        noisy = clip.xyz[k] + rng.normal(0, 0.01, size=(33, 3)).astype(np.float32)
        out = tracker.update([Pose(t, noisy, clip.visibility[k])], t)
        assert out is not None and out.t == t
        if k > 10:
            raw_err.append(np.abs(noisy[:, :2] - clip.xyz[k, :, :2]).mean())
            smooth_err.append(np.abs(out.xyz[:, :2] - clip.xyz[k, :, :2]).mean())
    # the live filter is tuned on measured jitter for little lag (docs/capture.md): it
    # removes about 15 % of this stream's jitter
    assert np.mean(smooth_err) < 0.9 * np.mean(raw_err)


def test_before_arming_the_central_largest_person_is_chosen(clip) -> None:
    x, v = clip.xyz[0], clip.visibility[0]
    main = _pose(x, v, 0.0)
    side = _pose(x, v, 0.0, dx=0.35, scale=0.7)  # off-centre and smaller
    assert selection_score(main) > selection_score(side)
    tracker = OperatorTracker(smooth=False)
    assert tracker.update([side, main], 0.0) is main
    assert tracker.update([main, side], 1 / 30) is main
    # Someone slightly better does not steal the choice (hysteresis) ...
    bigger = _pose(x, v, 0.0, dx=-0.3, scale=1.05)
    assert selection_score(bigger) < 1.25 * selection_score(main)
    assert tracker.update([bigger, main], 2 / 30) is main
    # ... but when the current one is gone, the best remaining person is taken.
    first_id = tracker.track_id
    assert tracker.update([side], 3 / 30) is side
    assert tracker.track_id == first_id + 1


def test_locked_operator_is_followed_and_never_swapped(clip) -> None:
    tracker = OperatorTracker(smooth=False)
    assert not tracker.lock_current()  # nobody followed yet: nothing to lock
    x, v = clip.xyz, clip.visibility
    operator = _pose(x[0], v[0], 0.0, dx=0.25, scale=0.8)  # off-centre, smaller
    tracker.update([operator], 0.0)  # only the operator in view when arming
    assert tracker.lock_current() and tracker.locked
    # The operator walks towards the centre; the other person stands nearby and scores
    # higher, but the lock keeps the operator.
    for k in range(1, 30):
        t = k / 30
        op = _pose(x[k], v[k], t, dx=0.25 - 0.005 * k, scale=0.8)
        crowd = _pose(x[k], v[k], t, dx=-0.3)
        assert selection_score(crowd) > selection_score(op)
        assert tracker.update([crowd, op], t) is op
    # The operator leaves the view: not found, and the other person is not taken.
    for k in range(30, 60):
        assert tracker.update([_pose(x[k], v[k], k / 30, dx=-0.3)], k / 30) is None
    # Back near where they left: found again, same track.
    track = tracker.track_id
    back = _pose(x[60], v[60], 2.0, dx=0.25 - 0.005 * 29 + 0.05, scale=0.8)
    assert tracker.update([_pose(x[60], v[60], 2.0, dx=-0.3), back], 2.0) is back
    assert tracker.track_id == track
    # Disarmed: selection falls back to the best-scoring person.
    tracker.unlock()
    crowd = _pose(x[61], v[61], 2.1, dx=-0.3)
    assert selection_score(crowd) > 1.25 * selection_score(back)
    assert tracker.update([crowd, back], 2.1) is crowd


def test_tracker_on_two_people_found_by_mediapipe() -> None:
    """Two real photos side by side: MediaPipe finds both people; the tracker takes the
    more central and larger one (the astronaut), keeps her when the picture shifts, and
    once locked reports "not found" rather than switching when she is covered."""
    sample = Path(matplotlib.get_data_path()) / "sample_data" / "grace_hopper.jpg"
    hopper = cv2.imread(str(sample))  # 600x512, head and shoulders
    astronaut = np.ascontiguousarray(skimage_data.astronaut()[:, :, ::-1])  # 512x512
    canvas = np.full((600, 1124, 3), 40, np.uint8)
    canvas[:, :512] = hopper
    canvas[44:556, 612:1124] = astronaut
    tracker = OperatorTracker()
    with PoseEstimator(num_poses=2) as est:
        poses = est.estimate(canvas, 0.0)
        assert len(poses) == 2
        chosen = tracker.update(poses, 0.0)
        assert chosen is not None and body_centre(chosen)[0] > 0.5  # the astronaut
        assert tracker.lock_current()
        for k in range(1, 4):
            t = k / 15
            chosen = tracker.update(est.estimate(np.roll(canvas, 10 * k, axis=1), t), t)
            assert chosen is not None and body_centre(chosen)[0] > 0.5
        covered = canvas.copy()
        covered[:, 560:] = 40
        t = 4 / 15
        others = est.estimate(covered, t)
        assert len(others) == 1 and body_centre(others[0])[0] < 0.5
        assert tracker.update(others, t) is None  # locked: Grace Hopper is not taken
        tracker.unlock()
        assert tracker.update(others, t + 1 / 15) is not None

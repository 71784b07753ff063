from __future__ import annotations

import numpy as np

from proxima.gesture.augment import mirror, rotate, time_warp, transitions
from proxima.gesture.features import (
    BodyImagePipeline,
    BodyPipeline,
    BodySmoothZPipeline,
    PaperPipeline,
    make_pipeline,
)
from proxima.gesture.geometry import rotation_matrix, to_metric
from proxima.gesture.windows import make_windows
from proxima.types import GESTURES


def _windows(laser_clips, view="f"):
    clips = [c for c in laser_clips if c.view == view]
    return make_windows(clips, stride=200)


def test_mirroring_swaps_only_left_and_right_moves(laser_clips) -> None:
    w = _windows(laser_clips)
    m = to_metric(w.xyz, w.aspect)
    m2, l2 = mirror(m, w.labels)
    names = {GESTURES[a]: GESTURES[b] for a, b in zip(w.labels, l2, strict=True)}
    assert names["move_to_left"] == "move_to_right" and names["move_to_right"] == "move_to_left"
    assert all(a == b for a, b in names.items() if a not in ("move_to_left", "move_to_right"))
    m3, l3 = mirror(m2, l2)
    np.testing.assert_allclose(m3, m, atol=1e-5)  # mirroring twice is the identity
    assert (l3 == w.labels).all()


def test_body_features_do_not_change_when_the_camera_turns(laser_clips) -> None:
    w = _windows(laser_clips)
    m = to_metric(w.xyz, w.aspect)
    turned = m @ rotation_matrix(0, np.deg2rad(50), 0).T  # another view of the same motion
    body = BodyPipeline()
    a, b = body.transform(m, w.has_z), body.transform(turned, w.has_z)
    np.testing.assert_allclose(a, b, atol=1e-3)
    assert a.shape == (len(w), 60, body.num_features)


def test_body_features_are_scale_and_position_free(laser_clips) -> None:
    w = _windows(laser_clips)
    m = to_metric(w.xyz, w.aspect)
    body = BodyPipeline()
    np.testing.assert_allclose(body.transform(m), body.transform(2.5 * m + 0.3), atol=1e-4)


def test_body_image_features_are_body_features_without_the_turn(laser_clips) -> None:
    w = _windows(laser_clips, "l")
    m = to_metric(w.xyz, w.aspect)
    image = make_pipeline("body-image", {})
    assert isinstance(image, BodyImagePipeline) and image.num_features == 80
    unturned = BodyPipeline().transform(m, np.zeros(len(w), dtype=bool))
    np.testing.assert_array_equal(image.transform(m, w.has_z), unturned)
    # a side view is near profile: turning it to face the camera changes the picture
    assert np.abs(BodyPipeline().transform(m, w.has_z) - unturned).max() > 0.5
    np.testing.assert_allclose(image.transform(m), image.transform(2.5 * m + 0.3), atol=1e-4)


def test_paper_scaling_is_fitted_on_training_data_only(laser_clips) -> None:
    w = _windows(laser_clips)
    m = to_metric(w.xyz, w.aspect)
    p = PaperPipeline().fit(m[:5])
    x = p.transform(m[:5])
    assert x.shape == (5, 60, 99) and x.min() >= 0 and x.max() <= 1 + 1e-6
    restored = PaperPipeline.from_state(p.state())
    np.testing.assert_allclose(restored.transform(m), p.transform(m), atol=1e-6)


def test_rotation_stays_within_range_and_keeps_bone_lengths(laser_clips) -> None:
    w = _windows(laser_clips)
    m = to_metric(w.xyz, w.aspect)
    r = rotate(m, np.random.default_rng(0), 15.0)
    bone = lambda x: np.linalg.norm(x[..., 13, :] - x[..., 15, :], axis=-1)  # noqa: E731
    np.testing.assert_allclose(bone(r), bone(m), rtol=1e-4, atol=1e-5)
    assert not np.allclose(r, m)


def test_time_warp_replays_windows_at_another_speed(laser_clips) -> None:
    # A clock for a window: every coordinate of frame t is t, so the warped values are
    # the (fractional) frame times each output frame was sampled at.
    clock = np.broadcast_to(np.arange(60.0)[None, :, None, None], (500, 60, 33, 3))
    sampled = time_warp(clock, np.random.default_rng(0), 0.3)[:, :, 0, 0]
    assert sampled.min() >= 0 and sampled.max() <= 59
    speed = np.diff(sampled, axis=1)
    inside = (sampled[:, 1:] > 0) & (sampled[:, 1:] < 59) & (sampled[:, :-1] > 0)
    per_window = [np.median(v[k]) for v, k in zip(speed, inside, strict=True) if k.any()]
    assert min(per_window) >= 0.7 - 1e-9 and max(per_window) <= 1.3 + 1e-9
    assert max(per_window) - min(per_window) > 0.4  # speeds vary from window to window
    w = _windows(laser_clips)
    m = to_metric(w.xyz, w.aspect)
    warped = time_warp(m, np.random.default_rng(1), 0.2)
    assert warped.shape == m.shape and not np.allclose(warped, m)


def test_transitions_join_two_gestures_of_one_scene(laser_clips) -> None:
    w = make_windows([c for c in laser_clips if c.view in ("f", "l")], stride=100)
    m = to_metric(w.xyz, w.aspect)
    out = transitions(m, w.labels, w.scene, np.random.default_rng(0), rate=1.0)
    assert out.shape == m.shape
    joined = 0
    for i in range(len(m)):
        # Each window now ends with its own first frames (half of it at least) ...
        new = next(n for n in range(60, 0, -1) if np.allclose(out[i, 60 - n :], m[i, :n]))
        assert 30 <= new < 60
        before = 60 - new - min(15, 60 - new)  # what precedes the 0.5 s move
        if not before:
            continue
        # ... after the last frames of a window of another gesture from the same camera.
        donors = [
            j for j in range(len(m))
            if w.scene[j] == w.scene[i] and w.labels[j] != w.labels[i]
            and np.allclose(m[j, 60 - before :], out[i, :before])
        ]  # fmt: skip
        assert donors, f"window {i} does not start inside another gesture of its scene"
        joined += 1
    assert joined > len(m) // 4
    assert set(w.scene) == {"laser/laser/f", "laser/laser/l"}


def test_smoothing_the_depth_keeps_body_features_and_damps_the_depth_jitter(laser_clips) -> None:
    w = _windows(laser_clips, "l")  # a side view: the turn mixes z into x most
    m = to_metric(w.xyz, w.aspect)
    smooth, body = make_pipeline("body-smooth-z", {}), BodyPipeline()
    assert isinstance(smooth, BodySmoothZPipeline) and smooth.num_features == body.num_features
    clean_s, clean_b = smooth.transform(m, w.has_z), body.transform(m, w.has_z)
    # LASER's depth is smooth: the averaged one moves the features little
    assert np.median(np.abs(clean_s - clean_b)) < 0.02
    # the live path's depth jitter (23 times x and y's): far less of it reaches the features
    noisy = m.copy()
    noisy[..., 2] += np.random.default_rng(0).normal(0.0, 0.05, noisy[..., 2].shape)
    err_s = np.abs(smooth.transform(noisy, w.has_z) - clean_s).mean()
    err_b = np.abs(body.transform(noisy, w.has_z) - clean_b).mean()
    assert err_s < 0.5 * err_b, (err_s, err_b)
    # a depth steady over the window is left as it is: then it is `body` exactly
    steady = m.copy()
    steady[..., 2] = m[:, :1, :, 2]
    np.testing.assert_allclose(smooth.transform(steady, w.has_z), body.transform(steady, w.has_z),
                               atol=1e-5)  # fmt: skip
    np.testing.assert_allclose(smooth.transform(m), smooth.transform(2.5 * m + 0.3), atol=1e-4)

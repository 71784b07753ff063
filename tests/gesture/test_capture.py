"""The capture model on the real LASER (and one UAV-Gesture) clips: each effect does what
it says, seeded runs repeat, bad parameters are refused, and the module's constants are
the ones the two measurements wrote."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from proxima.gesture.capture import (
    CONDITIONS,
    MAX_GAP_S,
    TRAIN_MAX_GAP_S,
    CaptureError,
    CaptureModel,
    condition,
    live_windows,
)
from proxima.gesture.capture import measured as m
from proxima.gesture.clip import Clip
from proxima.gesture.geometry import to_metric
from proxima.gesture.windows import make_windows

RESULTS = Path(__file__).resolve().parents[2] / "bench" / "results"
QUIET: dict[str, Any] = {"jitter": 0.0, "visibility_noise": 0.0}


@pytest.fixture(scope="module")
def clips(laser_clips) -> dict[str, Clip]:
    return {c.name: c for c in laser_clips}


@pytest.fixture(scope="module")
def hover_f(clips) -> Clip:
    return clips["DJI_0149_hover_f"]


def metric(xyz: np.ndarray, aspect: float = 16 / 9) -> np.ndarray:
    return to_metric(np.asarray(xyz, np.float64), aspect)


def torso2d(m: np.ndarray) -> np.ndarray:
    d = (m[..., 11, :2] + m[..., 12, :2] - m[..., 23, :2] - m[..., 24, :2]) / 2
    return np.linalg.norm(d, axis=-1)


def windows_of(clip: Clip, window: int = 60, stride: int = 10):
    return make_windows([clip], window=window, stride=stride)


def test_clean_changes_nothing(hover_f) -> None:
    w = windows_of(hover_f)
    model = condition("clean")
    x, v = model.apply_windows(w.xyz, w.vis, np.random.default_rng(0))
    np.testing.assert_allclose(x, w.xyz, atol=1e-6)
    np.testing.assert_allclose(v, w.vis, atol=1e-7)
    cap = model.apply_clip(hover_f, np.random.default_rng(0))
    np.testing.assert_array_equal(cap.frames, hover_f.frames)
    np.testing.assert_allclose(cap.xyz, hover_f.xyz, atol=1e-6)


def test_jitter_rms_is_the_requested_level_scaled_by_size_and_visibility(hover_f) -> None:
    w = windows_of(hover_f)
    relative = {}
    for height in (0.2, 0.6):
        geometry: dict[str, Any] = {"person_height": height, "visibility_noise": 0.0}
        base, _ = CaptureModel(jitter=0.0, **geometry).apply_windows(
            w.xyz, w.vis, np.random.default_rng(1)
        )
        noisy, vis = CaptureModel(jitter=2.0, **geometry).apply_windows(
            w.xyz, w.vis, np.random.default_rng(1)
        )
        m_base, m_noisy = metric(base), metric(noisy)
        torso = np.median(torso2d(m_base), axis=1)[:, None, None]
        np.testing.assert_allclose(m.STATURE_TORSO * torso, height, rtol=0.01)  # new height
        expected = 2.0 * m.jitter_torso(height) * torso * m.visibility_factor(vis)
        ratio = (m_noisy - m_base)[..., :2] / expected[..., None]
        assert np.sqrt(np.mean(ratio**2)) == pytest.approx(1.0, abs=0.02)
        scale = (torso * m.visibility_factor(vis))[..., None]  # the visibility part out
        relative[height] = np.sqrt(np.mean(((m_noisy - m_base)[..., :2] / scale) ** 2))
    # Relative to the body, the smaller person jitters more, by the measured law.
    law = m.jitter_torso(0.2) / m.jitter_torso(0.6)
    assert law > 2
    assert relative[0.2] / relative[0.6] == pytest.approx(law, rel=0.05)


def test_low_visibility_landmarks_jitter_more(clips) -> None:
    clip = clips["DJI_0150_hover_r"]  # side view: the far arm has low visibility
    w = windows_of(clip)
    base, _ = CaptureModel(jitter=0.0, visibility_noise=0.0).apply_windows(
        w.xyz, w.vis, np.random.default_rng(2)
    )
    noisy, vis = CaptureModel(visibility_noise=0.0).apply_windows(
        w.xyz, w.vis, np.random.default_rng(2)
    )
    step = np.abs(metric(noisy) - metric(base))[..., 1]
    low, high = vis < 0.5, vis > 0.95
    assert low.sum() > 100 and high.sum() > 100
    assert np.median(step[low]) > 4 * np.median(step[high])


@pytest.mark.parametrize("rho", [0.0, 0.6])
def test_jitter_correlation_in_time(hover_f, rho) -> None:
    w = windows_of(hover_f)
    base, _ = CaptureModel(jitter=0.0, visibility_noise=0.0).apply_windows(
        w.xyz, w.vis, np.random.default_rng(3)
    )
    noisy, _ = CaptureModel(jitter_corr=rho, visibility_noise=0.0).apply_windows(
        w.xyz, w.vis, np.random.default_rng(3)
    )
    d = (noisy - base)[..., :2]
    a, b = d[:, :-1].ravel(), d[:, 1:].ravel()
    assert np.corrcoef(a, b)[0, 1] == pytest.approx(rho, abs=0.05)


def test_roll_keeps_the_torso_length_in_metric_units(hover_f) -> None:
    w = windows_of(hover_f)
    x, _ = CaptureModel(roll_deg=15.0, **QUIET).apply_windows(
        w.xyz, w.vis, np.random.default_rng(4)
    )
    before, after = metric(w.xyz), metric(x)
    np.testing.assert_allclose(torso2d(after), torso2d(before), rtol=1e-4)

    # ... and turns the shoulder line by 15 degrees one way or the other.
    def angle(m: np.ndarray) -> np.ndarray:
        d = m[..., 11, :2] - m[..., 12, :2]
        return np.degrees(np.arctan2(d[..., 1], d[..., 0]))

    turn = (angle(after) - angle(before) + 180) % 360 - 180
    np.testing.assert_allclose(np.abs(turn), 15.0, atol=1e-3)


def test_elevation_shortens_the_torso_by_its_cosine(hover_f) -> None:
    w = windows_of(hover_f)
    for deg in (30.0, 45.0):
        x, _ = CaptureModel(elevation_deg=deg, **QUIET).apply_windows(
            w.xyz, w.vis, np.random.default_rng(5)
        )
        ratio = np.median(torso2d(metric(x)) / torso2d(metric(w.xyz)))
        assert ratio == pytest.approx(np.cos(np.radians(deg)), abs=0.05)
        # Looking down, the head comes nearer the camera than the hips.
        nose_z = metric(x)[..., 0, 2] - metric(x)[..., [23, 24], 2].mean(-1)
        nose_z0 = metric(w.xyz)[..., 0, 2] - metric(w.xyz)[..., [23, 24], 2].mean(-1)
        assert np.median(nose_z - nose_z0) < 0


def test_yaw_turns_only_data_with_depth(hover_f) -> None:
    w = windows_of(hover_f)
    model = CaptureModel(yaw_deg=40.0, **QUIET)
    turned, _ = model.apply_windows(w.xyz, w.vis, np.random.default_rng(6), has_z=True)
    flat, _ = model.apply_windows(w.xyz, w.vis, np.random.default_rng(6), has_z=False)
    np.testing.assert_allclose(flat, w.xyz, atol=1e-6)
    # The shoulder line shortens by about cos(40) in x (the front view faces the camera).
    width = np.abs(turned[..., 11, 0] - turned[..., 12, 0])
    width0 = np.abs(w.xyz[..., 11, 0] - w.xyz[..., 12, 0])
    assert np.median(width / width0) < 0.9


def test_frame_rate_and_drops_leave_the_right_timestamps(clips) -> None:
    clip = clips["DJI_0150_hover_r"]
    span = (clip.frames[-1] - 1) / 30
    cap = CaptureModel(fps=10.0, **QUIET).apply_clip(clip, np.random.default_rng(7))
    np.testing.assert_allclose(cap.t, (cap.frames - 1) / 10.0)
    assert cap.fps == 10.0
    assert np.array_equal(np.diff(cap.frames), np.ones(len(cap) - 1))
    assert len(cap) == int(span * 10) + 1
    # At 10 fps every third source row is a camera frame: the poses are those rows.
    np.testing.assert_allclose(cap.xyz, clip.xyz[::3][: len(cap)], atol=1e-6)
    dropped = CaptureModel(drop_rate=0.2, **QUIET).apply_clip(clip, np.random.default_rng(7))
    assert set(dropped.frames) <= set(clip.frames)
    assert len(dropped) / len(clip) == pytest.approx(0.8, abs=0.04)
    np.testing.assert_allclose(dropped.t, (dropped.frames - 1) / 30.0)


def test_frames_where_nobody_was_detected_stay_lost(clips) -> None:
    clip = max(clips.values(), key=lambda c: int(np.diff(c.frames).max()))  # slow_down_r
    gap = int(np.argmax(np.diff(clip.frames)))
    assert clip.frames[gap + 1] - clip.frames[gap] > 5  # a real gap in the recording
    lo, hi = (clip.frames[gap] - 1) / 30, (clip.frames[gap + 1] - 1) / 30
    cap = CaptureModel(fps=12.0, **QUIET).apply_clip(clip, np.random.default_rng(8))
    inside = (cap.t > lo + 1e-9) & (cap.t < hi - 1e-9)
    assert not inside.any()


def test_gaps_and_the_live_window_restart(hover_f) -> None:
    model = CaptureModel(gap_rate_hz=1.0, gap_s=(0.5, 0.5), **QUIET)
    cap = model.apply_clip(hover_f, np.random.default_rng(9))
    pauses = np.diff(cap.t)
    assert (pauses > 0.45).sum() >= 3  # gaps happened
    index = {round(t, 6): i for i, t in enumerate(cap.t)}

    def longest_pauses(**max_gap: float) -> list[float]:
        xyz, vis, end = live_windows(cap, size=60, stride=5, **max_gap)
        assert len(xyz) > 0 and xyz.shape[1:] == (60, 33, 3) and vis.shape[1:] == (60, 33)
        rows = [index[round(float(e), 6)] for e in end]
        return [float(np.diff(cap.t[i - 59 : i + 1]).max()) for i in rows]

    # the live window bridges half a second (MAX_GAP_S), a stricter one restarts there
    bridged, strict = longest_pauses(), longest_pauses(max_gap_s=0.25)
    assert 0.45 < max(bridged) <= MAX_GAP_S + 1e-9
    assert max(strict) <= 0.25 + 1e-9 and len(strict) < len(bridged)


def test_windows_at_a_lower_frame_rate_hold_every_third_row(hover_f) -> None:
    model = CaptureModel(fps=10.0, **QUIET)
    need = model.source_frames(60)
    assert need >= 3 * 59 + 1
    short_xyz, short_vis = _xv(hover_f, 60)
    with pytest.raises(CaptureError, match="cut"):
        model.apply_windows(short_xyz, short_vis, _rng())
    xyz, vis = _xv(hover_f, need)
    out, _ = model.apply_windows(xyz, vis, _rng(), window=60)
    rows = need - 1 - 3 * np.arange(59, -1, -1)
    np.testing.assert_allclose(out, xyz[:, rows], atol=1e-6)


@pytest.mark.parametrize("fps", [30.0, 10.0])
def test_dropped_frames_in_windows_are_skipped_rows(hover_f, fps) -> None:
    model = CaptureModel(fps=fps, drop_rate=0.3, **QUIET)
    xyz, vis = _xv(hover_f, model.source_frames(60))
    out, _ = model.apply_windows(xyz, vis, _rng(), window=60)
    step = round(30 / fps)
    skipped = False
    # Each pose is one source row (camera frames fall on rows here), in order, with
    # skips, and no pause over TRAIN_MAX_GAP_S (training windows keep to it).
    for n in range(len(out)):
        err = np.abs(out[n][:, None] - xyz[n][None]).max(axis=(2, 3))  # (60, S)
        rows = err.argmin(axis=1)
        assert err.min(axis=1).max() < 1e-6
        gaps = np.diff(rows)
        assert np.all(gaps % step == 0) and gaps.min() >= step
        assert gaps.max() / 30 <= TRAIN_MAX_GAP_S + 1e-9
        skipped |= bool(gaps.max() > step)
        assert rows[-1] >= xyz.shape[1] - 1 - 7  # ends within a pause of the window's end
    assert skipped


def test_legs_out_of_frame_get_low_visibility_and_leave_the_image(hover_f) -> None:
    model = CaptureModel(loss_rate=1.0, loss_parts=("legs",), loss_modes=("frame",),
                         loss_s=60.0, loss_cut=0.3, **QUIET)  # fmt: skip
    cap = model.apply_clip(hover_f, np.random.default_rng(10))
    mid = slice(30, len(cap) - 30)  # after the drift in
    feet = [27, 28, 29, 30, 31, 32]
    assert np.all(cap.xyz[mid][:, feet, 1] > 1.0)
    assert np.median(cap.visibility[mid][:, feet]) < 0.3
    assert np.median(hover_f.visibility[:, feet]) > 0.8
    assert np.median(cap.visibility[mid][:, [11, 12]]) > 0.8  # the shoulders stay seen


def test_an_arm_out_of_frame(hover_f) -> None:
    model = CaptureModel(loss_rate=1.0, loss_parts=("right_arm",), loss_modes=("frame",),
                         loss_s=60.0, loss_cut=0.5, **QUIET)  # fmt: skip
    cap = model.apply_clip(hover_f, np.random.default_rng(11))
    mid = slice(30, len(cap) - 30)  # after the drift in
    # The cut: halfway along the arm's widest reach from the shoulder (metric x).
    src = metric(hover_f.xyz)
    arm = [14, 16, 18, 20, 22]
    reach = src[:, arm, 0] - src[:, [12], 0]
    widest = reach.ravel()[np.abs(reach).argmax()]
    cut = np.median(src[:, 12, 0]) + 0.5 * widest
    beyond = (src[mid, 16, 0] - cut) * np.sign(widest) > 0  # the wrist past the cut
    assert beyond.sum() >= 30
    wrist = cap.xyz[mid][beyond, 16, 0]
    assert np.all((wrist < 0) | (wrist > 1))
    assert np.median(cap.visibility[mid][beyond, 16]) < 0.5
    assert np.median(cap.visibility[mid][:, 11]) > 0.8  # the other shoulder stays seen


def test_a_hidden_part_keeps_its_place_at_low_visibility(hover_f) -> None:
    model = CaptureModel(loss_rate=1.0, loss_parts=("left_arm",), loss_modes=("hidden",),
                         loss_s=60.0, **QUIET)  # fmt: skip
    cap = model.apply_clip(hover_f, np.random.default_rng(12))
    arm = [13, 15, 17, 19, 21]
    np.testing.assert_allclose(cap.xyz, hover_f.xyz, atol=1e-6)
    assert cap.visibility[:, arm].max() <= m.ABSENT_VISIBILITY[1] + 1e-6
    np.testing.assert_allclose(cap.visibility[:, 0], hover_f.visibility[:, 0], atol=1e-6)


def test_the_loss_condition_acts_through_the_lost_parts_jitter(hover_f) -> None:
    # A lost part keeps its place (MediaPipe's guess) at a visibility the classifier does
    # not read, so the condition runs at the measured jitter, as `distance` does: what a
    # lost part changes in the features is its larger jitter.
    for level in (1, 2, 3):
        assert condition("loss", level).jitter == condition("jitter", 1).jitter == 1.0
    hidden = CaptureModel(loss_rate=1.0, loss_parts=("left_arm",), loss_modes=("hidden",),
                          loss_s=60.0)  # fmt: skip
    seen = CaptureModel()
    arm, torso = [13, 15, 17, 19, 21], [0, 11, 12, 23, 24]

    def step_rms(model: CaptureModel, points: list[int]) -> float:
        cap = model.apply_clip(hover_f, np.random.default_rng(14))
        d2 = np.diff(metric(cap.xyz)[:, points, :2], n=2, axis=0)  # hover: still arms
        return float(np.sqrt(np.mean(d2**2)))

    assert step_rms(hidden, arm) > 3 * step_rms(seen, arm)  # measured: 5-6 times
    assert step_rms(hidden, torso) == pytest.approx(step_rms(seen, torso), rel=0.25)


def test_points_a_data_set_lacks_are_left_alone(uav_dir) -> None:
    from proxima.gesture.uavgesture import load_mat

    path = sorted(uav_dir.glob("joint_positions/hover/*/*.mat"))[0]
    clip = load_mat(path, "hover")
    cap = condition("field", 3).apply_clip(clip, np.random.default_rng(13))
    absent = clip.visibility[0] == 0
    assert absent.sum() >= 16
    assert np.all(cap.visibility[:, absent] == 0)
    assert np.all(cap.xyz[..., 2] == 0)  # no depth invented


def test_seeded_runs_repeat(hover_f) -> None:
    model = condition("field")
    xyz, vis = _xv(hover_f, model.source_frames(60))
    a = model.apply_windows(xyz, vis, np.random.default_rng(5), window=60)
    b = model.apply_windows(xyz, vis, np.random.default_rng(5), window=60)
    c = model.apply_windows(xyz, vis, np.random.default_rng(6), window=60)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.allclose(a[0], c[0])
    ca = model.apply_clip(hover_f, np.random.default_rng(5))
    cb = model.apply_clip(hover_f, np.random.default_rng(5))
    np.testing.assert_array_equal(ca.xyz, cb.xyz)
    np.testing.assert_array_equal(ca.t, cb.t)


@pytest.mark.parametrize("name", CONDITIONS)
def test_every_condition_runs_on_real_windows(clips, name) -> None:
    levels = (1,) if name == "clean" else (1, 2, 3)
    for level in levels:
        model = condition(name, level)
        w = make_windows(list(clips.values())[:6], window=model.source_frames(60), stride=40)
        x, v = model.apply_windows(w.xyz, w.vis, _rng(), aspect=w.aspect, has_z=w.has_z,
                                   window=60)  # fmt: skip
        assert x.shape == (len(w), 60, 33, 3) and v.shape == (len(w), 60, 33)
        assert np.isfinite(x).all() and (v >= 0).all() and (v <= 1).all()
    assert json.dumps(condition(name).describe())


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"roll_deg": 20.0}, "roll_deg"),
        ({"fps": 5.0}, "fps"),
        ({"elevation_deg": (30.0, 10.0)}, "above high"),
        ({"person_height": 2.0}, "person_height"),
        ({"jitter": -1.0}, "jitter"),
        ({"drop_rate": float("nan")}, "drop_rate"),
        ({"loss_parts": ("tail",)}, "loss_parts"),
        ({"loss_modes": ()}, "loss_modes"),
        ({"gap_s": "long"}, "gap_s"),
    ],
)
def test_bad_parameters_are_refused(kwargs, message) -> None:
    with pytest.raises(CaptureError, match=message):
        CaptureModel(**kwargs)


def test_bad_conditions_and_arrays_are_refused(hover_f) -> None:
    with pytest.raises(CaptureError, match="unknown capture condition 'fog'"):
        condition("fog")
    with pytest.raises(CaptureError, match="level must be 1, 2 or 3"):
        condition("roll", 4)
    with pytest.raises(CaptureError, match=r"xyz must be"):
        CaptureModel().apply_windows(np.zeros((2, 60, 17, 3)), np.zeros((2, 60, 17)), _rng())
    xyz, vis = _xv(hover_f, 60)
    with pytest.raises(CaptureError, match="one per window"):
        CaptureModel().apply_windows(xyz, vis, _rng(), aspect=np.ones(len(xyz) + 1))
    roll: Any = np.float32(5.0)  # numpy numbers are numbers too
    assert CaptureModel(roll_deg=roll).roll_deg == (5.0, 5.0)
    with pytest.raises(CaptureError, match="increasing"):
        CaptureModel().apply_sequence(np.zeros(5), hover_f.xyz[:5], hover_f.visibility[:5],
                                      _rng())  # fmt: skip


def test_constants_are_the_measured_ones() -> None:
    jitter = json.loads((RESULTS / "pose_jitter.json").read_text())["pooled"]
    law, knots = jitter["raw_size_law"], jitter["raw_visibility_knots"]
    bins = jitter["raw_visibility_factor"]
    p25, _, p75 = jitter["absent_legs_visibility_p25_p50_p75"]
    laser = json.loads((RESULTS / "capture_constants.json").read_text())
    edge = laser["edge_visibility"]["knots"]
    ambiguous = jitter["grace_hopper"]["raw_over_reference_law_median"]
    pairs = [  # (what the measurement wrote, the module's constant, tolerance)
        ([law["a"], law["b"], law["p"]], [m.JITTER_A, m.JITTER_B, m.JITTER_P], 0.01),
        ([ambiguous], [m.AMBIGUOUS_READING], 0.01),
        (knots["visibility"], list(m.VIS_FACTOR_AT), 0.01),
        (knots["factor"], list(m.VIS_FACTOR), 0.01),
        ([jitter["z_over_xy_median"]], [m.Z_OVER_XY], 0.01),
        ([b["visibility_step_rms"] for b in bins], list(m.VIS_STEP_RMS), 0.01),
        ([p25, p75], list(m.ABSENT_VISIBILITY), 0.01),
        ([jitter["filter_ratio_visible_median"]], [m.ONE_EURO_KEEPS], 0.02),
        ([laser["stature"]["stature_torso"]], [m.STATURE_TORSO], 0.001),
        ([k["median_distance"] for k in edge], list(m.EDGE_DISTANCE), 0.01),
        ([k["factor"] for k in edge], list(m.EDGE_FACTOR), 0.01),
    ]
    for wrote, constant, tol in pairs:
        assert wrote == pytest.approx(constant, rel=tol, abs=2e-3)
    assert jitter["reference_photo"] == "astronaut"
    assert abs(jitter["astronaut"]["autocorr_xy_visible_median"][0]) < 0.05  # JITTER_CORR 0
    assert m.JITTER_CORR == 0.0
    assert condition("jitter", 3).jitter == m.AMBIGUOUS_READING


def _rng() -> np.random.Generator:
    return np.random.default_rng(0)


def _xv(clip: Clip, window: int) -> tuple[np.ndarray, np.ndarray]:
    w = make_windows([clip], window=window, stride=25)
    return w.xyz, w.vis

"""Capture-augmented training windows, the live One Euro rule on them, and the fitted
temperature (gesture/robust.py, pose/one_euro.py, gesture/calibration.py), on real clips."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from proxima.gesture.calibration import fit_temperature, nll
from proxima.gesture.capture import condition
from proxima.gesture.classifier import GestureClassifier, save_checkpoint
from proxima.gesture.robust import (
    CAPTURE_MIX,
    CaptureSource,
    capture_windows,
    history_rows,
)
from proxima.gesture.train import TrainConfig, fit, predict_logits, softmax
from proxima.gesture.windows import WINDOW, make_windows, temporal_parts
from proxima.pose.one_euro import LIVE_ONE_EURO, OneEuroFilter, PoseSmoother, one_euro_windows

# A model trained without capture augmentation, unsure on noisy input (tests/data/README.md).
NO_CAPTURE = Path(__file__).resolve().parents[1] / "data" / "gesture-no-capture.pt"


@pytest.fixture(scope="module")
def parts(laser_clips) -> list:
    """The temporal training parts of six real clips (two views, three gestures)."""
    names = {"hover", "have_command", "move_to_left"}
    chosen = [c for c in laser_clips if c.gesture in names and c.view in ("f", "l")]
    return [temporal_parts(c, WINDOW)[0] for c in chosen]


def test_one_euro_windows_is_the_filter_of_the_live_path(parts) -> None:
    part = parts[0]
    t = (part.frames[:120] - 1) / 30.0
    x = part.xyz[:120].astype(np.float64)
    batch = one_euro_windows(x[None], t[None])[0]
    f = OneEuroFilter(LIVE_ONE_EURO.min_cutoff, LIVE_ONE_EURO.beta, LIVE_ONE_EURO.d_cutoff)
    ref = np.stack([f(row, ti) for row, ti in zip(x, t, strict=True)])
    assert np.abs(batch - ref).max() < 1e-12
    smoother = PoseSmoother()
    live = np.stack([smoother(row, ti) for row, ti in zip(x, t, strict=True)])
    assert np.abs(live - ref).max() < 1e-6  # float32
    # a pause over 0.5 s restarts it: the first pose after it passes unchanged
    t2 = t.copy()
    t2[60:] += 1.0
    out = one_euro_windows(x[None], t2[None])[0]
    assert np.array_equal(out[60], x[60]) and not np.allclose(out[61], x[61])


def test_capture_source_holds_the_windows_rows(parts) -> None:
    w = make_windows(parts, WINDOW, 4, 5)
    rows = history_rows(CAPTURE_MIX)
    src = CaptureSource.from_parts(parts, WINDOW, 4, 5, rows)
    assert len(src) == len(w) and rows > WINDOW + 15  # field's 15 fps needs history
    xyz, vis = src.rows(np.arange(len(w)), WINDOW)
    assert np.array_equal(xyz, w.xyz) and np.array_equal(vis, w.vis)
    longer, _ = src.rows(np.arange(len(w)), rows)  # the earliest windows: edge copies
    assert np.array_equal(longer[:, -WINDOW:], w.xyz)


def test_capture_augmentation_changes_the_training_windows(parts) -> None:
    w = make_windows(parts, WINDOW, 8, 5)
    src = CaptureSource.from_parts(parts, WINDOW, 8, 5, history_rows(CAPTURE_MIX))
    rng = np.random.default_rng(0)
    out = capture_windows(w, src, CAPTURE_MIX, rng)
    assert out.shape == w.xyz.shape and np.isfinite(out).all()
    step = np.abs(out - w.xyz).mean(axis=(1, 2, 3))
    assert (step > 1e-3).mean() > 0.7  # field 1 and 2 (80% of the mix) move every window
    again = capture_windows(w, src, CAPTURE_MIX, np.random.default_rng(1))
    assert not np.allclose(out, again)  # redrawn every epoch
    # the clean share is the recording through the live filter only, warmed up before it
    clean = capture_windows(w, src, [("clean", 1, 1.0)], rng)
    assert 0 < np.abs(clean - w.xyz).mean() < 0.003
    t = np.broadcast_to(np.arange(WINDOW + 15) / 30.0, (len(w), WINDOW + 15))
    ref = one_euro_windows(src.rows(np.arange(len(w)), WINDOW + 15)[0], t)[:, 15:]
    assert np.allclose(clean, ref, atol=1e-6)
    # field noise is larger than the filter's own change
    assert np.abs(out - w.xyz).mean() > 3 * np.abs(clean - w.xyz).mean()


def test_windows_without_history_lose_only_the_timing_effects(parts) -> None:
    w = make_windows(parts[:2], WINDOW, 8, 5)
    out = capture_windows(w, CaptureSource.from_windows(w), [("field", 1, 1.0)],
                          np.random.default_rng(0))  # fmt: skip
    assert out.shape == w.xyz.shape and np.abs(out - w.xyz).mean() > 1e-3
    assert condition("field", 1).timing


def test_the_time_clock_keeps_a_slow_cameras_window_on_the_recordings_clock(parts) -> None:
    # A 15 fps camera, nothing else (condition fps 2): its last 30 poses span 2 s, so the
    # window under the pose clock runs the gesture twice as fast; resampled to 30 per
    # second it stays near the recording's own last 30 rows (the live filter's lag and
    # the interpolation between every other row apart).
    w = make_windows(parts, 30, 8, 5)
    mix = [("fps", 2, 1.0)]
    src = CaptureSource.from_parts(parts, 30, 8, 5, history_rows(mix, 30))
    by_poses = capture_windows(w, src, mix, np.random.default_rng(0), 30)
    by_time = capture_windows(w, src, mix, np.random.default_rng(0), 30, clock="time")
    assert by_time.shape == by_poses.shape == w.xyz.shape
    moving = np.abs(np.diff(w.xyz, axis=1)).mean(axis=(1, 2, 3)) > 2e-3
    assert moving.sum() >= 10
    off_time = np.abs(by_time - w.xyz)[moving].mean()
    off_poses = np.abs(by_poses - w.xyz)[moving].mean()
    assert off_time < 0.2 * off_poses  # measured 0.0028 against 0.045
    # the training mix (three conditions): every window drawn, each clock
    full = CaptureSource.from_parts(parts, 30, 8, 5, history_rows(CAPTURE_MIX, 30))
    for clock in ("time", "mixed"):
        out = capture_windows(w, full, CAPTURE_MIX, np.random.default_rng(0), 30, clock=clock)
        assert np.isfinite(out).all() and np.abs(out).max() < 10
    # "mixed": each window one of the two (this condition draws no noise)
    mixed = capture_windows(w, src, mix, np.random.default_rng(0), 30, clock="mixed")
    as_time = np.all(np.isclose(mixed, by_time, atol=1e-6), axis=(1, 2, 3))
    as_poses = np.all(np.isclose(mixed, by_poses, atol=1e-6), axis=(1, 2, 3))
    assert np.all(as_time | as_poses) and 0.3 < as_time[moving].mean() < 0.7
    # at 30 fps with nothing lost the two clocks give the same windows
    clean = [("clean", 1, 1.0)]
    a = capture_windows(w, src, clean, np.random.default_rng(0), 30)
    b = capture_windows(w, src, clean, np.random.default_rng(0), 30, clock="time")
    assert np.array_equal(a, b)


def test_training_with_capture_runs_and_unknown_augment_is_refused(parts) -> None:
    from proxima.gesture.features import make_pipeline
    from proxima.gesture.geometry import to_metric
    from proxima.gesture.models import build_model

    w = make_windows(parts, WINDOW, 12, 5)
    pipeline = make_pipeline("body")
    pipeline.fit(to_metric(w.xyz, w.aspect))
    torch.manual_seed(0)
    model = build_model("tcn", num_features=pipeline.num_features)
    cfg = TrainConfig(epochs=1, threads=1)
    assert cfg.augment == "capture"  # the default
    src = CaptureSource.from_parts(parts, WINDOW, 12, 5, history_rows(cfg.capture_mix))
    history = fit(model, pipeline, w, None, cfg, source=src)
    assert len(history) == 1 and np.isfinite(history[0].train_loss)
    with pytest.raises(ValueError, match="augment 'bogus'"):
        fit(model, pipeline, w, None, TrainConfig(epochs=1, augment="bogus"))
    with pytest.raises(ValueError, match="window clock 'bogus'"):
        fit(model, pipeline, w, None, TrainConfig(epochs=1, window_clock="bogus"))


def test_temperature_is_fitted_on_held_out_windows_and_round_trips(
    laser_clips, tmp_path: Path
) -> None:
    shipped = GestureClassifier.load(NO_CAPTURE)
    assert shipped.temperature == 1.0  # made before calibration: uncalibrated
    # The shipped model on field-captured windows of real test parts: overconfident.
    rng = np.random.default_rng(0)
    tests = [temporal_parts(c, WINDOW)[1] for c in laser_clips if c.view == "f"]
    w = make_windows(tests, WINDOW, 6, 5)
    xyz, _ = condition("jitter", 2).apply_windows(w.xyz, w.vis, rng, aspect=w.aspect)
    logits = predict_logits(shipped.model, shipped.features(xyz, 16 / 9))
    half = np.arange(len(w)) % 2 == 0
    fitted = fit_temperature(logits[half], w.labels[half])
    t = fitted.temperature
    assert t > 0 and fitted.nll_after < fitted.nll_before
    held = ~half  # windows the fit never saw
    assert nll(logits[held], w.labels[held], t) < nll(logits[held], w.labels[held], 1.0)
    # stored in the checkpoint, applied by the live classifier
    blob = torch.load(NO_CAPTURE, map_location="cpu", weights_only=True)
    path = save_checkpoint(tmp_path / "c.pt", shipped.model, blob["model"], shipped.pipeline,
                           WINDOW, {}, t)  # fmt: skip
    loaded = GestureClassifier.load(path)
    assert loaded.temperature == pytest.approx(t)
    probs = loaded.predict(xyz[:8])
    assert np.allclose(probs, softmax(logits[:8], t), atol=1e-5)
    with pytest.raises(ValueError, match="temperature"):
        save_checkpoint(tmp_path / "d.pt", shipped.model, "tcn", shipped.pipeline, WINDOW, {}, 0.0)


def test_a_capture_mix_is_read_from_text_and_bad_entries_are_named() -> None:
    from proxima.gesture.robust import CAPTURE_MIX, parse_mix

    assert parse_mix("clean:1:0.2,field:1:0.4,field:2:0.4") == [list(m) for m in CAPTURE_MIX]
    for text, message in [("clean:1", "expected CONDITION:LEVEL:SHARE"),
                          ("field:x:1", "LEVEL is an integer"),
                          ("fog:1:1", "unknown capture condition 'fog'"),
                          ("clean:1:-1", "shares must be >= 0")]:  # fmt: skip
        with pytest.raises(ValueError, match=message):
            parse_mix(text)


def test_train_refuses_a_bad_capture_mix_before_loading_data(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from proxima.cli import app

    out = tmp_path / "m.pt"
    result = CliRunner().invoke(app, ["train", "--out", str(out), "--capture-mix", "field:2"])
    assert result.exit_code == 2 and "capture mix 'field:2'" in result.output
    assert not out.exists()

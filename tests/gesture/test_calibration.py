"""The calibration split `calibrate:<split>:<seconds>` on the real clips, and fine-tuning
its inner split's model (`proxima train --init`)."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from proxima.gesture.clip import DataError
from proxima.gesture.windows import make_windows, parse_calibration, split_clips


@pytest.fixture(scope="module")
def uav_clips(uav_dir):
    from proxima.gesture.uavgesture import load_uavgesture_dir

    return load_uavgesture_dir(uav_dir)


def _rows(parts) -> set[tuple[str, int]]:
    return {(p.name, int(f)) for p in parts for f in p.frames}


def _check_calibration(clips, inner: str, seconds: float, fps: float, uav_dir=None) -> None:
    held_out = {c.name: c for c in split_clips(clips, inner, uav_dir=uav_dir).test}
    parts = split_clips(clips, f"calibrate:{inner}:{seconds:g}", uav_dir=uav_dir)
    n = round(seconds * fps)
    assert {c.name for c in parts.calibration} == set(held_out)  # every held-out clip
    for cal in parts.calibration:
        clip = held_out[cal.name]
        start = clip.frames[0]
        # exactly the rows of the first n frames, counted by frame number
        assert np.array_equal(cal.frames, clip.frames[clip.frames < start + n])
        assert any(c is cal for c in parts.train)
    for te in parts.test:
        clip = held_out[te.name]
        start = clip.frames[0]
        # every row from one window (60 frames) after the calibration on, and only those
        assert np.array_equal(te.frames, clip.frames[clip.frames >= start + n + 60])
    assert not _rows(parts.train) & _rows(parts.test)
    # the test windows never touch a calibration frame
    w = make_windows(parts.test, stride=1)
    assert len(w) > 0


def test_calibration_on_the_unseen_view_trains_the_first_seconds(laser_clips) -> None:
    _check_calibration(laser_clips, "cross-view:l", 5, 30.0)
    parts = split_clips(laser_clips, "calibrate:cross-view:l:5")
    # the other views train whole, as in cross-view:l
    assert {c.view for c in parts.train} == {"f", "r", "l"}
    assert {c.view for c in parts.test} == {"l"} and len(parts.test) == 13
    # a clip that loses frames: move_upward_l starts at frame 3, so its 5 s end at 152
    cal = next(c for c in parts.calibration if c.name.endswith("move_upward_l"))
    assert cal.frames[0] == 3 and cal.frames[-1] <= 152


def test_calibration_on_unseen_people_counts_25_fps(uav_clips, uav_dir) -> None:
    _check_calibration(uav_clips, "uav-gesture:2", 5, 25.0, uav_dir)
    parts = split_clips(uav_clips, "calibrate:uav-gesture:2:5", uav_dir=uav_dir)
    length = {c.name: len(c) for c in split_clips(uav_clips, "uav-gesture:2", uav_dir=uav_dir).test}
    # UAV-Gesture has no gaps: 125 rows, or the whole of a shorter clip (which then tests
    # nothing)
    assert all(len(c) == min(125, length[c.name]) for c in parts.calibration)
    assert {c.name for c in parts.test} == {n for n, k in length.items() if k > 125 + 60}
    # the unseen people are in training only through their first 5 s
    unseen = {c.subject for c in parts.calibration}
    assert all(c.name in length for c in parts.train if c.subject in unseen)
    assert all(len(c) <= 125 for c in parts.train if c.subject in unseen)


@pytest.mark.parametrize("inner", ["cross-view:f", "uav-gesture:3"])
def test_zero_seconds_is_the_inner_split(laser_clips, uav_clips, uav_dir, inner) -> None:
    clips = laser_clips if inner.startswith("cross") else uav_clips
    a = split_clips(clips, inner, uav_dir=uav_dir)
    b = split_clips(clips, f"calibrate:{inner}:0", uav_dir=uav_dir)
    assert [c.name for c in a.test] == [c.name for c in b.test]
    assert all(np.array_equal(x.frames, y.frames) for x, y in zip(a.test, b.test, strict=True))
    assert _rows(a.train) == _rows(b.train) and not b.calibration


@pytest.mark.parametrize(
    ("split", "message"),
    [
        ("calibrate:cross-view:l:-1", "seconds field must be a number >= 0"),
        ("calibrate:cross-view:l:five", "seconds field 'five' is not a number"),
        ("calibrate:cross-view:l:nan", "seconds field must be a number >= 0"),
        ("calibrate:cross-view:l", "seconds field 'l' is not a number"),
        ("calibrate:5", "use calibrate:<split>:<seconds>"),
        ("calibrate:temporal:5", "inner split 'temporal' must hold out whole clips"),
        ("calibrate:nonsense:5", "inner split 'nonsense' must hold out whole clips"),
        ("calibrate:cross-view:x:5", "the view must be f, l or r"),
        ("calibrate:cross-view:l:1000", "leaves no test frames"),
    ],
)
def test_bad_calibration_splits_name_the_field(laser_clips, split, message) -> None:
    with pytest.raises(DataError, match=message):
        split_clips(laser_clips, split)


def test_the_seconds_are_the_last_field() -> None:
    assert parse_calibration("calibrate:uav-gesture:2:2.5") == ("uav-gesture:2", 2.5)
    assert parse_calibration("cross-view:l") is None


def test_the_cli_names_a_bad_field(laser_dir, tmp_path) -> None:
    from proxima.cli import app

    args = ["train", "--data", str(laser_dir), "--out", str(tmp_path / "m.pt")]
    result = CliRunner().invoke(app, [*args, "--split", "calibrate:cross-view:l:x"])
    assert result.exit_code == 2
    assert "seconds field 'x' is not a number" in result.output
    result = CliRunner().invoke(
        app, [*args, "--split", "calibrate:cross-view:l:5", "--calibration-share", "1.5"]
    )
    assert result.exit_code == 2
    assert "calibration share 1.5: must lie between 0 and 1" in result.output


@pytest.mark.slow
def test_fine_tune_the_inner_model_and_score_the_remainder(
    uav_dir, uav_clips, small_checkpoint, tmp_path
) -> None:
    """Train uav-gesture:2, fine-tune it with its people's first 5 s (`--init`), score
    the rest; the temporal (or shipped) model is refused as a starting point; protocols
    accept the split."""
    from proxima.cli import app
    from proxima.evaluation.metrics import evaluate_checkpoint
    from proxima.evaluation.protocols import run_protocols
    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.train import TrainConfig

    base, tuned = tmp_path / "base.pt", tmp_path / "tuned.pt"
    common = ["--data", str(uav_dir), "--epochs", "1", "--stride", "20", "--threads", "1"]
    r = CliRunner().invoke(app, ["train", *common, "--split", "uav-gesture:2", "--out", str(base)])
    assert r.exit_code == 0, r.output
    split = "calibrate:uav-gesture:2:5"
    r = CliRunner().invoke(app, ["train", *common, "--split", split, "--out", str(tuned),
                                 "--init", str(base)])  # fmt: skip
    assert r.exit_code == 0, r.output
    meta = GestureClassifier.load(tuned).metadata
    assert meta["init"] == str(base) and meta["calibration_repeats"] >= 1
    a, b = GestureClassifier.load(base), GestureClassifier.load(tuned)
    assert any(
        not np.array_equal(x.detach().numpy(), y.detach().numpy())
        for x, y in zip(a.model.parameters(), b.model.parameters(), strict=True)
    )  # it trained
    m = evaluate_checkpoint(tuned, [str(uav_dir)], split)
    parts = split_clips(uav_clips, split, uav_dir=uav_dir)
    assert m["windows"] == len(make_windows(parts.test, stride=3))
    other = ["--out", str(tmp_path / "x.pt"), "--init", str(small_checkpoint)]
    r = CliRunner().invoke(app, ["train", *common, "--split", split, *other])
    assert r.exit_code == 2 and "trained on split 'temporal', not 'uav-gesture:2'" in r.output
    rows = run_protocols(
        [split], "tcn", [str(uav_dir)], TrainConfig(epochs=1, stride=20, threads=1)
    )
    assert rows[0]["split"] == split and rows[0]["windows"] == m["windows"]


def test_the_calibration_share_sets_how_often_its_clips_repeat(laser_clips) -> None:
    from proxima.gesture.workflow import calibration_fit_parts

    parts = split_clips(laser_clips, "calibrate:cross-view:l:5")
    calib = {id(c) for c in parts.calibration}
    n = {}
    for share in (0.25, 0.5, 0.75):
        fit, val, _ = calibration_fit_parts(parts, stride=4, max_gap=5, share=share)
        n_calib = len(make_windows([c for c in fit if id(c) in calib], stride=4))
        n[share] = n_calib / len(make_windows(fit, stride=4))
        assert not any(id(c) in calib for c in val)  # validation never holds them
    # each share lands near its target (whole repeats round it) and they order as asked
    assert n[0.25] < n[0.5] < n[0.75]
    for share, got in n.items():
        assert abs(got - share) < 0.1, (share, got)
    for bad in (0.0, 1.0, -0.5):
        with pytest.raises(DataError, match="calibration share"):
            calibration_fit_parts(parts, stride=4, max_gap=5, share=bad)

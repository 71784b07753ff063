"""Console samples as a data source: samples stored through the console's own store
(from real LASER landmarks) load through `--data samples:DB` for `proxima evaluate` and
`proxima train`; the calibration's take split and fine-tuning on such takes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from proxima.cli import app
from proxima.gesture.classifier import GestureClassifier, default_checkpoint
from proxima.gesture.clip import DataError
from proxima.gesture.console_samples import frame_numbers, load_console_samples
from proxima.gesture.datasets import load_data
from proxima.gesture.take_calibration import MIN_TAKE_FRAMES, calibrate_takes, split_take
from proxima.gesture.windows import WINDOW
from proxima.store.base import make_engine, make_sessionmaker
from proxima.store.migrations import upgrade
from proxima.store.samples import add_sample, review_sample

GESTURES = ("hover", "wave_off", "move_ahead")


def _store(db_path: Path, laser_clips, frames: int = 240) -> list[int]:  # type: ignore[no-untyped-def]
    """Store a take of each of GESTURES (left view) as console samples: two kept, one
    pending (never read), and a deleted one."""
    engine = make_engine(db_path)
    upgrade(engine)
    ids = []
    with make_sessionmaker(engine)() as db:
        for k, g in enumerate(GESTURES):
            clip = next(c for c in laser_clips if c.gesture == g and c.view == "l")
            part = clip.slice(30, 30 + frames)
            times = 100.0 + (part.frames - part.frames[0]) / 30.0
            s = add_sample(
                db,
                stream="left",
                drone="second",
                xyz=part.xyz,
                visibility=part.visibility,
                times=times,
                created_by="t",
            )
            if k < 2:
                review_sample(db, s, status="kept", label=g, by="t")
            ids.append(s.id)
        gone = add_sample(
            db,
            stream="left",
            drone="second",
            xyz=part.xyz[:80],
            visibility=part.visibility[:80],
            times=times[:80],
            label="land",
        )
        review_sample(db, gone, status="deleted", label=None, by="t")
    engine.dispose()
    return ids


def test_kept_samples_load_as_console_clips(tmp_path: Path, laser_clips) -> None:  # type: ignore[no-untyped-def]
    db = tmp_path / "console.db"
    ids = _store(db, laser_clips)
    clips = load_console_samples(db)
    assert [(c.gesture, c.source, c.view, c.subject) for c in clips] == [
        ("hover", "console", "left", "second"),
        ("wave_off", "console", "left", "second"),
    ]
    assert clips[0].name == f"console-{ids[0]}-left-hover"
    assert clips[0].xyz.shape == (240, 33, 3) and clips[0].xyz.dtype == np.float32
    # The LASER clip's own frame numbering survives the round trip through stream times.
    src = next(c for c in laser_clips if c.gesture == "hover" and c.view == "l").slice(30, 270)
    np.testing.assert_array_equal(clips[0].frames, src.frames - src.frames[0] + 1)
    np.testing.assert_allclose(clips[0].xyz, src.xyz, atol=1e-6)
    data = load_data([f"samples:{db}"])
    assert [c.name for c in data.clips] == [c.name for c in clips]
    assert len(data.fingerprint()) == 64
    with pytest.raises(DataError, match="no kept samples of drone 'main'"):
        load_console_samples(db, drone="main")
    with pytest.raises(DataError, match="no console database"):
        load_data([f"samples:{tmp_path / 'missing.db'}"])


def test_frame_numbers_follow_the_stream_clock() -> None:
    np.testing.assert_array_equal(
        frame_numbers(np.array([5.0, 5.0333, 5.1334, 5.1667])), [1, 2, 5, 6]
    )
    # a faster stream's rows never share a number
    assert list(frame_numbers(np.arange(6) / 60.0)) == [1, 2, 3, 4, 5, 6]


@pytest.mark.slow
def test_train_and_evaluate_read_console_samples(tmp_path: Path, laser_clips) -> None:  # type: ignore[no-untyped-def]
    db = tmp_path / "console.db"
    _store(db, laser_clips)
    runner = CliRunner()
    out = tmp_path / "metrics.json"
    r = runner.invoke(
        app,
        [
            "evaluate",
            "--checkpoint",
            str(default_checkpoint()),
            "--data",
            f"samples:{db}",
            "--json",
            str(out),
        ],
    )
    assert r.exit_code == 0, r.output
    metrics = json.loads(out.read_text())
    assert metrics["clips"] == 2 and metrics["windows"] > 0
    assert set(metrics["per_view"]) == {"left"}
    ckpt = tmp_path / "m.pt"
    r = runner.invoke(
        app,
        [
            "train",
            "--data",
            f"samples:{db}",
            "--out",
            str(ckpt),
            "--epochs",
            "1",
            "--stride",
            "8",
            "--threads",
            "1",
        ],
    )
    assert r.exit_code == 0, r.output
    meta = GestureClassifier.load(ckpt).metadata
    assert meta["data"] == [str(db)] and meta["train_windows"] > 0


def test_take_split_leaves_a_window_between_training_and_held_out(laser_clips) -> None:  # type: ignore[no-untyped-def]
    clip = next(c for c in laser_clips if c.gesture == "hover" and c.view == "f")
    train, held = split_take(clip.slice(0, 210))
    assert (len(train), len(held)) == (210 - 63 - WINDOW, 63)
    assert held.frames[0] - train.frames[-1] > WINDOW
    with pytest.raises(DataError, match=f"at least {MIN_TAKE_FRAMES}"):
        split_take(clip.slice(0, MIN_TAKE_FRAMES - 1))


@pytest.mark.slow
def test_calibrating_on_takes_scores_before_and_after(
    tmp_path: Path, laser_clips, shipped_member
) -> None:  # type: ignore[no-untyped-def]
    """The shipped ensemble has each member fine-tuned and stays an ensemble; one model
    stays one model. Both keep their temperatures."""
    from proxima.gesture.ensemble import EnsembleClassifier, load_checkpoint

    takes = [
        next(c for c in laser_clips if c.gesture == g and c.view == "r").slice(20, 230)
        for g in GESTURES
    ]
    seen: list[tuple[int, int]] = []
    member = [0]
    res = calibrate_takes(
        default_checkpoint(),
        takes,
        tmp_path / "cal.pt",
        epochs=2,
        threads=1,
        on_epoch=lambda e, n, loss: seen.append((member[0], e)),
        on_member=lambda i, n: member.__setitem__(0, i),
    )
    tuned, shipped = load_checkpoint(res.checkpoint), load_checkpoint(default_checkpoint())
    assert isinstance(tuned, EnsembleClassifier) and isinstance(shipped, EnsembleClassifier)
    n = len(shipped.members)
    assert seen == [(i, e) for i in range(1, n + 1) for e in (1, 2)] and res.epochs == 2
    assert set(res.before["per_gesture"]) == set(res.after["per_gesture"]) == set(GESTURES)
    assert res.before["windows"] == res.after["windows"] > 0
    assert tuned.metadata["held_out_after"] == res.after
    assert [m.temperature for m in tuned.members] == [m.temperature for m in shipped.members]
    assert all(m.metadata["split"] == "console-calibration" for m in tuned.members)

    one = calibrate_takes(shipped_member, takes, tmp_path / "one.pt", epochs=1, threads=1)
    clf = GestureClassifier.load(one.checkpoint)
    assert clf.metadata["held_out_after"] == one.after and one.epochs == 1
    assert clf.temperature == GestureClassifier.load(shipped_member).temperature

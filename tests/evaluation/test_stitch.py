"""Stitched replay streams: held-out rows, renumbered frames, transitions, blanks, truth."""

import json

import numpy as np
import pytest

from proxima.evaluation.stitch import (
    Blank,
    StitchError,
    parse_blank,
    parse_plan,
    stitch_views,
    truth_path_for,
)
from proxima.ingest import open_source
from proxima.pose import FEET

PLAN = [("have_command", 3.0), ("move_to_left", 4.0), ("hover", 3.0)]


def test_rows_come_from_the_test_part_and_views_share_timing(laser_clips) -> None:
    streams = stitch_views(laser_clips, PLAN, views=("f", "r"), part="test", seed=3)
    f, r = streams["f"], streams["r"]
    by_name = {c.name: c for c in laser_clips}
    for stream in (f, r):
        assert [s.gesture for s in stream.segments] == [g for g, _ in PLAN]
        assert np.all(np.diff(stream.frames) > 0) and stream.frames[0] == 1
        for seg in stream.segments:
            n = len(by_name[seg.clip])
            assert seg.rows[0] >= round(0.7 * n), f"{seg.clip} rows {seg.rows} not held out"
            assert seg.rows[1] <= n
    assert [(s.onset_t, s.end_t) for s in f.segments] == [(s.onset_t, s.end_t) for s in r.segments]
    # 0.5 s transitions: the second gesture starts 0.5 s after the first one ends.
    assert f.segments[1].onset_t == pytest.approx(f.segments[0].end_t + 0.5)


def test_transition_moves_smoothly_between_the_two_poses(laser_clips) -> None:
    s = stitch_views(laser_clips, PLAN[:2], views=("f",), seed=0)["f"]
    start = round(s.segments[0].end_t * 30)
    trans = s.xyz[start - 1 : start + 16]  # last pose, 15 transition frames, next pose
    steps = np.abs(np.diff(trans, axis=0)).max(axis=(1, 2))
    jump = np.abs(trans[-1] - trans[0]).max()
    assert steps.max() < 0.25 * jump  # no frame jumps most of the way at once


def test_blanks_and_written_files(laser_clips, tmp_path) -> None:
    blanks = {"f": [Blank(2.0, 4.0, "feet"), Blank(6.0, 6.5, "drop")]}
    s = stitch_views(laser_clips, PLAN, views=("f",), blanks=blanks, seed=1)["f"]
    t = (s.frames - 1) / s.fps
    inside = (t >= 2.0) & (t < 4.0)
    assert np.all(s.visibility[np.ix_(inside, list(FEET))] == 0)
    assert not np.any((t >= 6.0) & (t < 6.5))
    truth = s.write(tmp_path / "x.csv")
    assert truth == truth_path_for(tmp_path / "x.csv")
    doc = json.loads(truth.read_text())
    assert [b["kind"] for b in doc["blanks"]] == ["feet", "drop"]
    with open_source(f"replay:{tmp_path / 'x.csv'}", realtime=False) as src:
        frames = list(src)
    assert len(frames) == len(s.frames)
    assert frames[-1].t == pytest.approx(t[-1])


def test_bad_requests_say_what_is_wrong(laser_clips) -> None:
    with pytest.raises(StitchError, match="unknown gesture 'jump'"):
        parse_plan("have_command:3,jump:2")
    with pytest.raises(StitchError, match="SECONDS > 0"):
        parse_plan("hover:0")
    with pytest.raises(StitchError, match="START:END"):
        parse_blank("later", "feet")
    with pytest.raises(StitchError, match="blank kind"):
        parse_blank("1:2", "hands")
    with pytest.raises(StitchError, match="no clip of 'hover' in view"):
        stitch_views(laser_clips, [("hover", 2.0)], views=("x",))


@pytest.mark.slow
def test_stitch_command_writes_one_stream_per_view(laser_dir, tmp_path) -> None:
    from typer.testing import CliRunner

    from proxima.cli import app

    args = [
        "stitch",
        "--out",
        str(tmp_path / "s.csv"),
        "--script",
        "have_command:3,hover:3",
        "--view",
        "f",
        "--view",
        "r",
        "--blank",
        "f:feet:1:2",
        "--data",
        str(laser_dir),
    ]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    for view in ("f", "r"):
        truth = json.loads((tmp_path / f"s.{view}.truth.json").read_text())
        assert [s["gesture"] for s in truth["segments"]] == ["have_command", "hover"]
        assert truth["view"] == view and truth["part"] == "test"
    assert json.loads((tmp_path / "s.f.truth.json").read_text())["blanks"][0]["kind"] == "feet"
    bad = CliRunner().invoke(
        app,
        [
            "stitch",
            "--out",
            str(tmp_path / "b.csv"),
            "--script",
            "hover:3",
            "--blank",
            "r:feet:1:2",
            "--data",
            str(laser_dir),
        ],
    )
    assert bad.exit_code == 2 and "VIEW:KIND:START:END" in bad.output

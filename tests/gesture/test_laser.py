from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from proxima.cli import app
from proxima.gesture.clip import DataError
from proxima.gesture.laser import load_laser_csv
from proxima.types import GESTURES

SAMPLE = "DJI_0149_hover_f.MP4.csv"


def test_loads_every_clip_with_label_view_and_33_landmarks(laser_clips) -> None:
    assert len(laser_clips) == 39
    assert sum(len(c) for c in laser_clips) == 28856  # data-notes.md
    assert {c.gesture for c in laser_clips} == set(GESTURES)
    assert {c.view for c in laser_clips} == {"f", "l", "r"}
    for c in laser_clips:
        assert c.xyz.shape == (len(c), 33, 3) and np.isfinite(c.xyz).all()


def test_counter_frame_gaps_are_kept(laser_clips) -> None:
    clip = next(c for c in laser_clips if c.name == "DJI_0171_move_upward_r")
    missing = int((np.diff(clip.frames) - 1).sum())
    assert missing == 64  # data-notes.md: 64 frames missing in 19 gaps


def _broken_copy(laser_dir: Path, tmp_path: Path, name: str, edit) -> Path:
    lines = (laser_dir / SAMPLE).read_text().splitlines(keepends=True)
    lines = edit(lines)
    out = tmp_path / name
    out.write_text("".join(lines))
    return out


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda ls: [ls[0].replace(",z,", ",depth,"), *ls[1:]], ":1: missing column(s) z"),
        (lambda ls: [*ls[:5], ls[5].replace("0.", "abc", 1), *ls[6:]], ":6: column"),
        (lambda ls: ls[:1] + ls[2:], ":2: frame 1 has 32 landmarks"),
    ],
    ids=["missing-column", "non-numeric", "32-landmarks"],
)
def test_bad_rows_name_file_and_line(laser_dir, tmp_path, edit, message) -> None:
    path = _broken_copy(laser_dir, tmp_path, SAMPLE, edit)
    with pytest.raises(DataError) as err:
        load_laser_csv(path)
    assert str(path) in str(err.value) and message in str(err.value)


def test_unknown_gesture_in_file_name(laser_dir, tmp_path) -> None:
    path = tmp_path / "DJI_0999_barrel_roll_f.MP4.csv"
    shutil.copy(laser_dir / SAMPLE, path)
    with pytest.raises(DataError, match="unknown gesture 'barrel_roll'"):
        load_laser_csv(path)


def test_cli_reports_bad_data_and_exits_non_zero(laser_dir, tmp_path, small_checkpoint) -> None:
    _broken_copy(laser_dir, tmp_path, SAMPLE, lambda ls: ls[:1] + ls[2:])
    result = CliRunner().invoke(
        app, ["evaluate", "--checkpoint", str(small_checkpoint), "--data", str(tmp_path),
              "--split", "all", "--json", str(tmp_path / "m.json")],
    )  # fmt: skip
    assert result.exit_code == 2
    assert "frame 1 has 32 landmarks" in result.output

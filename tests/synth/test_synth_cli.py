"""`proxima synth` on the command line."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from proxima.cli import app


def test_synth_writes_clips_and_a_manifest(tmp_path: Path) -> None:
    out = tmp_path / "set"
    args = ["synth", "--out", str(out), "--clips", "14", "--seed", "2",
            "--views", "front:-10..10:0..10", "--views", "above:0..360:30..60:5..8"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "wrote 14 clips" in result.output and f"--data synth:{out}" in result.output
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["views"] == ["front:-10..10:0..10", "above:0..360:30..60:5..8"]
    assert [s["view"] for s in manifest["scenes"]] == ["front", "above"]
    assert len(list(out.glob("DJI_*.MP4.csv"))) == sum(
        1 for e in manifest["clip_list"] if e["file"]
    )
    assert manifest["command"].startswith("proxima ")  # from sys.argv, as `train` records it


def test_synth_rejects_bad_views_and_folders(tmp_path: Path) -> None:
    r = CliRunner().invoke(app, ["synth", "--out", str(tmp_path / "a"), "--views", "front:0"])
    assert r.exit_code == 2 and "expected NAME:AZIMUTH:ELEVATION" in r.output
    r = CliRunner().invoke(app, ["synth", "--out", str(tmp_path / "a"), "--resolution", "big"])
    assert r.exit_code == 2 and "WIDTHxHEIGHT" in r.output
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "x.txt").write_text("")
    r = CliRunner().invoke(app, ["synth", "--out", str(tmp_path / "b"), "--clips", "1"])
    assert r.exit_code == 2 and "not an empty folder" in r.output

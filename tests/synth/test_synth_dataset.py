"""Synthetic data sets on disk: the CSV round trip through the real LASER loader, the
manifest, determinism with a seed, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from proxima.gesture.clip import DataError
from proxima.gesture.laser import load_laser_csv, load_laser_dir
from proxima.synth import dataset
from proxima.synth.dataset import MANIFEST, generate, load_synth_dir
from proxima.synth.views import parse_view
from proxima.types import GESTURES


def test_csvs_read_back_through_the_laser_loader(synth_dir: Path) -> None:
    manifest = json.loads((synth_dir / MANIFEST).read_text())
    clips = {c.name: c for c in load_synth_dir(synth_dir)}
    assert len(clips) == 39
    for entry in manifest["clip_list"]:
        raw = load_laser_csv(synth_dir / entry["file"])  # the loader of the real data set
        clip = clips[entry["name"]]
        assert raw.gesture == clip.gesture == entry["gesture"]
        assert raw.view == clip.view == entry["view"]
        np.testing.assert_array_equal(raw.frames, clip.frames)
        np.testing.assert_allclose(raw.xyz, clip.xyz)
        assert raw.xyz.shape == (len(raw), 33, 3) and len(raw) == entry["detected"] > 60
        assert np.all((raw.visibility >= 0) & (raw.visibility <= 1))
        assert clip.source == "synth" and clip.subject == entry["subject"]
    # The folder also reads as plain LASER CSVs (source laser): the manifest is what
    # makes them synthetic, and load_data looks for it first (test_synth_splits.py).
    assert {c.source for c in load_laser_dir(synth_dir)} == {"laser"}


def test_manifest_records_bodies_cameras_and_gestures(synth_dir: Path) -> None:
    m = json.loads((synth_dir / MANIFEST).read_text())
    assert m["format"] == "proxima-synth/1" and m["seed"] == 7 and m["clips"] == 39
    assert [s["view"] for s in m["scenes"]] == ["front", "right", "left"]
    assert [s["laser_view"] for s in m["scenes"]] == ["f", "r", "l"]
    for s in m["scenes"]:
        assert 1.4 < s["body"]["stature"] < 2.1 and s["body"]["handedness"] in ("left", "right")
        assert set(s["camera"]) >= {"position", "yaw_deg", "pitch_deg", "roll_deg", "hfov_deg"}
    by_gesture = [e["gesture"] for e in m["clip_list"]]
    assert by_gesture == list(GESTURES) * 3  # spread evenly, in scenes of 13
    for e in m["clip_list"]:
        idle, gesture = e["segments"]
        assert idle["label"] == "" and gesture["label"] == e["gesture"]
        assert idle["end"] == gesture["start"] and gesture["end"] == e["frames"]
        assert e["steps"][1]["gesture"] == e["gesture"]


def test_same_seed_same_files_and_clips_do_not_depend_on_n(tmp_path: Path) -> None:
    a = generate(tmp_path / "a", 13, seed=3)
    b = generate(tmp_path / "b", 13, seed=3)
    c = generate(tmp_path / "c", 26, seed=3)
    d = generate(tmp_path / "d", 13, seed=4)
    for entry in a["clip_list"]:
        f = entry["file"]
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes()
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "c" / f).read_bytes()
        assert (tmp_path / "a" / f).read_bytes() != (tmp_path / "d" / f).read_bytes()
    assert a["scenes"] == b["scenes"] == c["scenes"][:1]
    assert a["scenes"] != d["scenes"]


def test_views_and_bad_input(tmp_path: Path) -> None:
    v = parse_view("above:0..360:30..60:5..9")
    assert v.azimuth == (0, 360) and v.elevation == (30, 60) and v.distance == (5, 9)
    assert parse_view(v.spec()) == v
    for bad, msg in (("front", "expected NAME"), ("f:a..b:0", "not a number"),
                     ("f:20..10:0", "LO <= HI"), ("f:0:95", "elevation"),
                     ("f:0:0:0.1", "distance")):  # fmt: skip
        with pytest.raises(ValueError, match=msg):
            parse_view(bad)
    with pytest.raises(ValueError, match="at least 1"):
        generate(tmp_path / "x", 0)
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="not an empty folder"):
        generate(other, 1)
    assert (other / "notes.txt").read_text() == "mine"  # left alone
    done = tmp_path / "done"
    generate(done, 2, views=[parse_view("front:0:10")])
    with pytest.raises(ValueError, match="--overwrite"):
        generate(done, 2)
    m = generate(done, 3, overwrite=True)
    assert len(list(done.glob("*.MP4.csv"))) == 3 and m["clips"] == 3
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp left


def test_a_missing_or_wrong_file_is_named(tmp_path: Path) -> None:
    out = tmp_path / "s"
    m = generate(out, 2)
    first = m["clip_list"][0]["file"]
    (out / first).unlink()
    with pytest.raises(DataError, match=f"{first}: listed in the manifest but missing"):
        load_synth_dir(out)
    (out / MANIFEST).write_text("{not json")
    with pytest.raises(DataError, match="unreadable manifest"):
        load_synth_dir(out)


def test_a_variant_changes_only_its_own_gestures_clips(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Part of the `have_command` clips take its variant (the manifest says which); the
    variant's own draw leaves every clip of the other gestures as it was without it."""
    m = generate(tmp_path / "with", clips=52, seed=5)
    monkeypatch.setattr(dataset, "VARIANT_SHARE", 0.0)
    generate(tmp_path / "without", clips=52, seed=5)
    for e in m["clip_list"]:
        same = (tmp_path / "with" / e["file"]).read_bytes() == (
            tmp_path / "without" / e["file"]
        ).read_bytes()
        form = e["steps"][1]["variant"]
        assert same == (not form), e["name"]
        assert not form or e["gesture"] == "have_command"
    assert sum(e["steps"][1]["variant"] for e in m["clip_list"]) >= 1

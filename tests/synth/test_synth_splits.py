"""Synthetic clips in the splits: training only, never in a test part, never in a real
scene; `--data synth:DIR` resolves and loads them."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from proxima.gesture.clip import DataError
from proxima.gesture.data_source import resolve_dataset
from proxima.gesture.datasets import load_data
from proxima.gesture.windows import make_windows, split_clips


@pytest.fixture(scope="module")
def mixed(laser_dir: Path, uav_dir: Path, synth_dir: Path):
    return load_data([str(laser_dir), str(uav_dir), f"synth:{synth_dir}"])


@pytest.mark.parametrize(
    "split", ["temporal", "cross-view:f", "cross-view:l", "cross-view:r", "uav-gesture:1", "all"]
)
def test_no_synthetic_window_in_any_test_part(mixed, split: str) -> None:
    parts = split_clips(mixed.clips, split, uav_dir=mixed.uav_dir)
    assert not [c.name for c in parts.test if c.source == "synth"]
    test_w = make_windows(parts.test, stride=10)
    assert not [s for s in test_w.scene if s.startswith("synth/")]
    synth = [c for c in mixed.clips if c.source == "synth"]
    trained = {c.name: len(c) for c in parts.train if c.source == "synth"}
    assert trained == {c.name: len(c) for c in synth}  # every synthetic clip, whole
    if split != "all":
        assert len(test_w) > 0 and {c.source for c in parts.test} <= {"laser", "uav-gesture"}


def test_synthetic_scenes_are_their_own(mixed) -> None:
    real = {c.scene for c in mixed.clips if c.source != "synth"}
    synth = {c.scene for c in mixed.clips if c.source == "synth"}
    assert len(synth) == 3 and not real & synth
    assert all(s.startswith("synth/synth-s7-p") for s in synth)
    by_scene = {}
    for c in mixed.clips:
        if c.source == "synth":
            by_scene.setdefault(c.scene, set()).add(c.gesture)
    assert all(len(g) == 13 for g in by_scene.values())  # each person makes every gesture


def test_synth_prefix_and_detection(synth_dir: Path, laser_dir: Path, tmp_path: Path) -> None:
    assert resolve_dataset(f"synth:{synth_dir}") == synth_dir
    plain = load_data([str(synth_dir)]).clips  # a plain path is recognised by its manifest
    assert {c.source for c in plain} == {"synth"}
    with pytest.raises(DataError, match="does not exist"):
        resolve_dataset(f"synth:{tmp_path / 'nope'}")
    with pytest.raises(DataError, match="not a synthetic data set"):
        resolve_dataset(f"synth:{laser_dir}")
    with pytest.raises(DataError, match="synthetic clips never test"):
        split_clips(plain, "temporal")
    copy = tmp_path / "copy"
    shutil.copytree(synth_dir, copy)
    (copy / "manifest.json").unlink()  # without its manifest it is LASER-format CSVs
    assert {c.source for c in load_data([str(copy)]).clips} == {"laser"}

from __future__ import annotations

import numpy as np

from proxima.gesture.skeleton import COMMON, OPENPOSE_TO_MEDIAPIPE
from proxima.gesture.uavgesture import load_split, load_uavgesture_dir


def test_loads_all_clips_onto_the_mediapipe_layout(uav_dir) -> None:
    clips = load_uavgesture_dir(uav_dir)
    assert len(clips) == 119
    assert sum(len(c) for c in clips) == 37151
    assert len({c.subject for c in clips}) > 5  # several people
    for c in clips:
        assert np.isfinite(c.xyz).all()  # missing joints are filled, never NaN
        # only the 17 mapped landmarks are ever visible
        assert c.visibility[:, [i for i in range(33) if i not in COMMON]].max() == 0
    assert len(COMMON) == 17 == len(OPENPOSE_TO_MEDIAPIPE)


def test_missing_joints_are_masked_and_interpolated(uav_dir) -> None:
    clips = load_uavgesture_dir(uav_dir)
    vis = np.concatenate([c.visibility[:, list(COMMON)] for c in clips])
    missing = 1 - vis.mean()
    assert 0.002 < missing < 0.02  # data-notes.md: about 0.6% of joints missing


def test_left_right_labels_follow_the_laser_convention(uav_dir) -> None:
    clips = {c.name: c for c in load_uavgesture_dir(uav_dir)}
    # The upstream folder move_to_left holds what LASER calls move_to_right.
    assert clips["S1_moveToLeft_HD"].gesture == "move_to_right"
    assert clips["S1_moveToRight_HD"].gesture == "move_to_left"


def test_official_splits_are_subject_wise(uav_dir) -> None:
    for split in (2, 3):
        train, test = load_split(uav_dir, split)
        assert len(test) == 33
        subjects = lambda names: {n.split("_")[0] for n in names}  # noqa: E731
        assert not subjects(train) & subjects(test)

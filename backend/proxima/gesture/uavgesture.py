"""Loader for UAV-Gesture (Perera et al. 2018): OpenPose COCO-18 joints in pixels of
1920x1080 video, several subjects, official subject-wise splits.

Joints are mapped onto MediaPipe's 33-landmark layout (see skeleton.py) so that both
data sets flow through the same windows, features and models.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from proxima.gesture.clip import Clip, DataError
from proxima.gesture.skeleton import HAND_WRIST, HANDS, MIRROR, OPENPOSE_TO_MEDIAPIPE
from proxima.types import NUM_LANDMARKS

WIDTH, HEIGHT = 1920, 1080
FOLDER_TO_GESTURE = {"landing_direction": "land_direction"}
# UAV-Gesture's move_to_left is LASER's move_to_right (data-notes.md): the arm that swings
# is the other one. Proxima's labels follow the LASER set, so these two swap on loading.
LABEL_SWAP = {"move_to_left": "move_to_right", "move_to_right": "move_to_left"}
_SUBJECT = re.compile(r"^(S\d+)_")


def _fill_missing(track: np.ndarray, present: np.ndarray) -> np.ndarray:
    """Linear interpolation over time for frames where a joint is missing; a joint never
    seen in the clip stays NaN (the caller falls back to a neighbour joint)."""
    out = track.copy()
    t = np.arange(len(track))
    if present.any():
        for d in range(track.shape[1]):
            out[:, d] = np.interp(t, t[present], track[present, d])
    else:
        out[:] = np.nan
    return out


def load_mat(path: str | Path, gesture: str) -> Clip:
    """One clip from its `.mat` file (`pos_img`: (2, 18, T) pixels; (0, 0) = missing).

    Raises:
        DataError: unreadable file, or `pos_img` missing or of the wrong shape.
    """
    from scipy.io import loadmat

    path = Path(path)
    try:
        mat = loadmat(path)
    except Exception as exc:  # scipy raises several types for a bad file
        raise DataError(f"{path}: not a readable MATLAB file ({exc})") from exc
    pos = mat.get("pos_img")
    if pos is None or pos.ndim != 3 or pos.shape[:2] != (2, 18):
        shape = None if pos is None else pos.shape
        raise DataError(f"{path}: field 'pos_img' must be (2, 18, T), got {shape}")
    joints = np.transpose(pos, (2, 1, 0)).astype(np.float64)  # (T, 18, 2)
    present = np.any(joints != 0, axis=2)  # (T, 18)
    T = joints.shape[0]
    xyz = np.zeros((T, NUM_LANDMARKS, 3), np.float32)
    vis = np.zeros((T, NUM_LANDMARKS), np.float32)
    for op, mp in OPENPOSE_TO_MEDIAPIPE.items():
        filled = _fill_missing(joints[:, op], present[:, op])
        xyz[:, mp, 0] = filled[:, 0] / WIDTH
        xyz[:, mp, 1] = filled[:, 1] / HEIGHT
        vis[:, mp] = present[:, op]
    # A joint never detected in the whole clip (e.g. the right ear in 3 clips): take its
    # mirror twin so the skeleton stays complete; visibility stays 0.
    for mp in OPENPOSE_TO_MEDIAPIPE.values():
        if np.isnan(xyz[:, mp]).any():
            xyz[:, mp] = xyz[:, MIRROR[mp]]
    # No hand points in OpenPose's body model: put them on their wrist, which the body
    # pipeline reads as "no hand shape seen" (zero offset).
    xyz[:, list(HANDS)] = xyz[:, list(HAND_WRIST)]
    if np.isnan(xyz).any():
        raise DataError(f"{path}: a joint and its mirror twin are never detected")
    folder = FOLDER_TO_GESTURE.get(gesture, gesture)
    label = LABEL_SWAP.get(folder, folder)
    name = path.stem
    m = _SUBJECT.match(name)
    return Clip(
        name=name,
        gesture=label,
        view="f",
        subject=m.group(1) if m else "?",
        source="uav-gesture",
        frames=np.arange(1, T + 1),
        xyz=xyz,
        visibility=vis,
        aspect=WIDTH / HEIGHT,
        has_z=False,
    )


def load_uavgesture_dir(path: str | Path) -> list[Clip]:
    """Every clip under `joint_positions/<gesture>/<clip>/<clip>.mat`, sorted by name.

    Raises:
        DataError: no clip found, or a bad one.
    """
    root = Path(path)
    files = sorted(root.glob("joint_positions/*/*/*.mat"))
    if not files:
        raise DataError(f"{root}: no UAV-Gesture clips (joint_positions/<gesture>/<clip>/*.mat)")
    return [load_mat(f, f.parent.parent.name) for f in files]


def load_split(path: str | Path, split: int) -> tuple[set[str], set[str]]:
    """(train clip names, test clip names) of official split 1, 2 or 3.

    Raises:
        DataError: unknown split number or missing split files.
    """
    if split not in (1, 2, 3):
        raise DataError(f"UAV-Gesture has splits 1, 2 and 3, not {split}")
    folder = Path(path) / "splits"
    train: set[str] = set()
    test: set[str] = set()
    for kind, dest in (("train", train), ("test", test)):
        files = sorted(folder.glob(f"*_{kind}_split{split}.txt"))
        if not files:
            raise DataError(f"{folder}: no *_{kind}_split{split}.txt files")
        for f in files:
            dest.update(line.strip() for line in f.read_text().splitlines() if line.strip())
    return train, test


def is_uavgesture_dir(path: str | Path) -> bool:
    return (Path(path) / "joint_positions").is_dir()

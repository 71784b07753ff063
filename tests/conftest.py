"""Shared fixtures: the real data sets in ../shared (tests never download)."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
LASER_DIR = SHARED / "datasets" / "laser-uav-gesture"
UAV_DIR = SHARED / "datasets" / "uav-gesture"


@pytest.fixture(scope="session")
def laser_dir() -> Path:
    assert LASER_DIR.is_dir(), f"tests need the LASER data set at {LASER_DIR}"
    return LASER_DIR


@pytest.fixture(scope="session")
def uav_dir() -> Path:
    assert UAV_DIR.is_dir(), f"tests need the UAV-Gesture data set at {UAV_DIR}"
    return UAV_DIR


@pytest.fixture(scope="session")
def laser_clips(laser_dir: Path):
    from proxima.gesture.laser import load_laser_dir

    return load_laser_dir(laser_dir)

"""Fixtures for the engine tests: the shipped gesture checkpoint and stitched streams."""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def checkpoint() -> Path:
    """The shipped model (`models/gesture-default.pt`); PROXIMA_TEST_CHECKPOINT overrides."""
    from proxima.gesture.classifier import default_checkpoint

    path = Path(os.environ.get("PROXIMA_TEST_CHECKPOINT") or default_checkpoint())
    assert path.is_file(), f"the engine tests need the gesture checkpoint at {path}"
    return path


@pytest.fixture(scope="session")
def classifier(checkpoint: Path):
    import torch

    from proxima.engine import load_classifier

    torch.set_num_threads(1)
    return load_classifier(checkpoint)

"""Fixtures for the scenario tests: the gesture checkpoint the live engine runs."""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def checkpoint() -> Path:
    """The shipped model (`models/gesture-default.pt`); PROXIMA_TEST_CHECKPOINT overrides."""
    from proxima.gesture.classifier import default_checkpoint

    path = Path(os.environ.get("PROXIMA_TEST_CHECKPOINT") or default_checkpoint())
    assert path.is_file(), f"the scenario tests need the gesture checkpoint at {path}"
    return path

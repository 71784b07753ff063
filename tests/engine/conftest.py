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


# Tests that pin an exact command script of the engine's mechanics (handover, arming
# before commands, the operator lock) use this fixed model, so that retraining the
# shipped model does not rewrite their scripts: trained without capture augmentation
# (tests/data/README.md). The shipped model's own live figures are measured by
# `proxima robustness` and the scenario tests.
REFERENCE_CHECKPOINT = Path(__file__).resolve().parents[1] / "data" / "gesture-no-capture.pt"


@pytest.fixture(scope="session")
def reference_checkpoint() -> Path:
    return REFERENCE_CHECKPOINT


@pytest.fixture(scope="session")
def reference_classifier():
    import torch

    from proxima.engine import load_classifier

    torch.set_num_threads(1)
    return load_classifier(REFERENCE_CHECKPOINT)

"""A small synthetic data set, made once per test session."""

from __future__ import annotations

from pathlib import Path

import pytest

from proxima.synth.dataset import generate


@pytest.fixture(scope="session")
def synth_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("synth") / "set"
    generate(out, 39, seed=7)  # three scenes: one per default view, every gesture in each
    return out

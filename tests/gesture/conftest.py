from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from proxima.cli import app


@pytest.fixture(scope="session")
def small_checkpoint(tmp_path_factory, laser_dir) -> Path:
    """A TCN trained briefly by the real CLI on the temporal split (coarse windows)."""
    out = tmp_path_factory.mktemp("ckpt") / "tcn.pt"
    result = CliRunner().invoke(
        app, ["train", "--data", str(laser_dir), "--model", "tcn", "--split", "temporal",
              "--out", str(out), "--epochs", "4", "--stride", "12", "--threads", "1"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    return out

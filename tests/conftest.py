"""Shared fixtures: the real data sets in ../shared (tests never download: the pose
model and the data sets resolve offline, `PROXIMA_OFFLINE`)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# Subprocesses the tests start inherit it too.
os.environ["PROXIMA_OFFLINE"] = "1"

# A test that uses one of these is slow wherever it lies: it trains a model, starts a
# simulated vehicle or drives a browser. Tests that start other processes or servers
# (the CLI, RTSP, the wheel) carry `@pytest.mark.slow` themselves; `make test-fast`
# runs the rest.
SLOW_FIXTURES = frozenset({"small_checkpoint", "start_sim", "browser"})


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if SLOW_FIXTURES.intersection(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)


# `make test` runs two pytest-xdist workers. A test module stays on one worker, so its
# module fixtures run once and its tests keep their order; the console's tests (API,
# browser, demo, 3D view) all share one worker because the console binds the fixed
# MAVLink ports (udpin:127.0.0.1:14550 and up) that two consoles at once would fight
# over. (xdist's own `--dist loadgroup` ignored its group marks with pytest 9.2 here.)
CONSOLE_DIRS = frozenset({"api", "ui", "demo", "viz"})


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
    from xdist.scheduler import LoadScopeScheduling

    class ModuleOrConsole(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            parts = path.split("/")
            return "console" if len(parts) > 2 and parts[1] in CONSOLE_DIRS else path

    return ModuleOrConsole(config, log)


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


@pytest.fixture(scope="session")
def small_checkpoint(tmp_path_factory, laser_dir: Path) -> Path:
    """A TCN trained briefly by the real CLI on the temporal split (coarse windows)."""
    from typer.testing import CliRunner

    from proxima.cli import app

    out = tmp_path_factory.mktemp("ckpt") / "tcn.pt"
    result = CliRunner().invoke(
        app, ["train", "--data", str(laser_dir), "--model", "tcn", "--split", "temporal",
              "--out", str(out), "--epochs", "4", "--stride", "12", "--threads", "1"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="session")
def degraded_checkpoint(tmp_path_factory: pytest.TempPathFactory, shipped_member: Path) -> Path:
    """The shipped ensemble's first member with Gaussian noise (half each tensor's
    spread, seed 0) on its weights: a real one-model checkpoint the engine runs,
    measurably worse (0.48 against the shipped ensemble's 0.85 window accuracy on the
    console's synthetic held-out set; wave_off recall 0.57 against 0.89), standing in
    for a poorly trained candidate (a federated run's model) in promotion tests."""
    import torch

    member = torch.load(shipped_member, map_location="cpu", weights_only=True)
    gen = torch.Generator().manual_seed(0)
    for k, v in member["state_dict"].items():
        if v.is_floating_point() and v.numel() > 1:
            w = v.float()
            noise = 0.5 * w.std() * torch.randn(w.shape, generator=gen)
            member["state_dict"][k] = (w + noise).half()
    path = tmp_path_factory.mktemp("degraded") / "gesture-degraded.pt"
    torch.save(member, path)
    return path


@pytest.fixture(scope="session")
def shipped_member(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped ensemble's first member as a one-model checkpoint file (what a run
    that starts from one model, or fine-tunes one, takes)."""
    from proxima.gesture.classifier import write_blob
    from proxima.gesture.ensemble import load_checkpoint, members_of

    member = members_of(load_checkpoint(None))[0]
    return write_blob(tmp_path_factory.mktemp("member") / "gesture-member.pt", member.blob())

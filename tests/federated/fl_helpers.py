"""Helpers shared by the federated tests."""

from __future__ import annotations

from proxima.federated.config import FLConfig


def fast_config(**overrides: object) -> FLConfig:
    """Two rounds, coarse windows, one local epoch: seconds per round on this machine."""
    values: dict = {
        "rounds": 2,
        "local_epochs": 1,
        "stride": 12,
        "test_stride": 12,
        "min_clients": 3,
        "include_samples": False,
        "wait_timeout_s": 120.0,
        "round_timeout_s": 120.0,
    }
    values.update(overrides)
    return FLConfig(**values)  # type: ignore[arg-type]

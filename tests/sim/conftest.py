"""Fixtures for the closed-loop simulator's tests: a clean registry of scenes and
vehicles for every test (the registry is per process)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest


@pytest.fixture(autouse=True)
def clean_registry() -> Iterator[None]:
    from proxima.sim import registry

    registry.reset()
    yield
    registry.reset()

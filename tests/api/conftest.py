"""Fixtures for the console API tests: a fresh SQLite database per test, a supervisor and
a viewer, and the app behind Starlette's TestClient."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from api_helpers import ADMIN, VIEWER, Api, login, make_settings
from fastapi.testclient import TestClient

from proxima.api import create_app
from proxima.events import EventBus
from proxima.store.users import Role, create_user


@pytest.fixture
def api(tmp_path: Path) -> Iterator[Api]:
    settings = make_settings(tmp_path)
    bus = EventBus()
    app = create_app(settings, bus)
    with app.state.console.sessions() as db:
        create_user(db, VIEWER[0], VIEWER[1], Role.VIEWER)
    with TestClient(app) as client:
        yield Api(client, bus, settings, login(client, ADMIN), login(client, VIEWER))
        app.state.console.recorder.join()


@pytest.fixture(scope="session")
def checkpoint_path() -> Path:
    """The gesture checkpoint the live engine runs (PROXIMA_TEST_CHECKPOINT, else the
    shipped one)."""
    import os

    from proxima.gesture.classifier import default_checkpoint

    path = Path(os.environ.get("PROXIMA_TEST_CHECKPOINT") or default_checkpoint())
    assert path.is_file(), f"this test needs the gesture checkpoint at {path}"
    return path

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

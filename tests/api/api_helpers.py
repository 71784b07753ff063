"""Helpers shared by the console API tests: users, settings on a fresh database with two
streams replayed from the LASER set, logging in."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fastapi.testclient import TestClient

from proxima.events import EventBus
from proxima.settings import Settings

ADMIN = ("chief", "correct-horse-battery")
VIEWER = ("watcher", "viewer-password-42")
LASER = Path(__file__).resolve().parents[3] / "shared" / "datasets" / "laser-uav-gesture"


def laser_clip(name: str) -> Path:
    """A LASER clip by its gesture_view suffix, e.g. `move_to_left_f`."""
    from proxima.gesture.data_source import resolve_laser_dir

    root = Path(resolve_laser_dir(None))
    matches = sorted(root.glob(f"DJI_*_{name}.MP4.csv"))
    assert matches, f"no LASER clip *_{name}.MP4.csv in {root}"
    return matches[0]


def make_settings(tmp_path: Path, **overrides: object) -> Settings:
    base: dict = {
        "admin_user": ADMIN[0],
        "admin_password": ADMIN[1],
        "server": {"db_path": str(tmp_path / "console.db"), "viser_enabled": False},
        "streams": [
            {"name": "front", "uri": f"replay:{laser_clip('hover_f')}@30", "drone": "main"},
            {
                "name": "left",
                "uri": f"replay:{laser_clip('hover_l')}@30",
                "drone": "second",
                "priority": 1,
            },
        ],
        "drones": [
            {"name": "main", "connection": "udpin:127.0.0.1:14550"},
            {"name": "second", "connection": "udpin:127.0.0.1:14560", "sysid": 2},
        ],
    }
    base.update(overrides)
    return Settings.load(config=None, **base)


@dataclass
class Api:
    client: TestClient
    bus: EventBus
    settings: Settings
    admin: dict[str, str]
    viewer: dict[str, str]

    @property
    def console(self):  # type: ignore[no-untyped-def]
        return self.client.app.state.console


def login(client: TestClient, user: tuple[str, str]) -> dict[str, str]:
    r = client.post("/api/auth/login", json={"username": user[0], "password": user[1]})
    assert r.status_code == 200, r.text
    return {"Authorization": f"Bearer {r.json()['token']}"}

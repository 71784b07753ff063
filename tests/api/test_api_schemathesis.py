"""The OpenAPI schema tells the truth: schemathesis (all its default checks, every phase)
fuzzes the console in-process and finds nothing, not only no 5xx.

The app has every subsystem an action route needs, so none answers 503: a runner that
trains nothing (`runner_double.py`: a fuzzed request must never start real training)
and the real emergency-stop service over in-memory drone links. The routes that end the
caller's own session or account run as users made for them: logout with a fresh login
per request, the password change as a user of its own, disabling as a second
supervisor against a user made to be disabled; everything else as the supervisor.
Bounded: at most `MAX_EXAMPLES` cases per operation and phase.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import schemathesis
from api_helpers import ADMIN, VIEWER, make_settings
from fastapi import FastAPI
from fastapi.testclient import TestClient
from runner_double import NoTrainingRunner
from schemathesis.config import SchemathesisConfig
from schemathesis.engine import Status, events, from_schema

from proxima.api import create_app
from proxima.drone.controller import DroneController, EmergencyStopService
from proxima.drone.memory import MemoryLink
from proxima.events import EventBus
from proxima.store.users import Role, create_user

MAX_EXAMPLES = 25
SEED = 20251202
LEAVER = ("leaver", "leaves-every-time-1")
CHANGER = ("changer", "changes-nothing-22")
DISABLER = ("disabler", "disables-a-target-3")
TARGET = ("target", "to-be-disabled-444")
OWN_SESSION = [
    ("POST", "/api/auth/logout"),
    ("POST", "/api/auth/password"),
    ("POST", "/api/users/{username}/disable"),
]


def fuzz_app(tmp_path: Path) -> FastAPI:
    settings = make_settings(tmp_path, server={
        "db_path": str(tmp_path / "console.db"),
        "viser_enabled": False,
        "models_dir": str(tmp_path / "models"),
    })  # fmt: skip
    bus = EventBus()
    links = {d.name: MemoryLink(d.name) for d in settings.drones}
    estop = EmergencyStopService(DroneController(links, safety=settings.safety, bus=bus))
    runner = NoTrainingRunner([d.name for d in settings.drones])
    app = create_app(settings, bus, training=runner, estop=estop)
    with app.state.console.sessions() as db:
        create_user(db, VIEWER[0], VIEWER[1], Role.VIEWER)
        for user, role in ((LEAVER, Role.VIEWER), (CHANGER, Role.VIEWER),
                           (DISABLER, Role.SUPERVISOR), (TARGET, Role.VIEWER)):  # fmt: skip
            create_user(db, user[0], user[1], role)
    return app


def token(client: TestClient, user: tuple[str, str]) -> str:
    r = client.post("/api/auth/login", json={"username": user[0], "password": user[1]})
    assert r.status_code == 200, r.text
    return r.json()["token"]


def bearer(get_token: Callable[[], str]) -> type:
    class Bearer:
        def get(self, case: Any, ctx: Any) -> str:
            return get_token()

        def set(self, case: Any, data: str, ctx: Any) -> None:
            case.headers = {**(case.headers or {}), "Authorization": f"Bearer {data}"}

    return Bearer


class Run:
    """One schemathesis run's tally: cases sent, and each failed check."""

    def __init__(self) -> None:
        self.cases = 0
        self.failures: Counter[str] = Counter()
        self.errors: list[str] = []

    def add(self, event: events.EngineEvent) -> None:
        if isinstance(event, events.ScenarioFinished):
            self.cases += len(event.recorder.cases)
            for checks in event.recorder.checks.values():
                for check in checks:
                    if check.status is not Status.SUCCESS and check.failure_info is not None:
                        failure = check.failure_info.failure
                        what = " ".join(f"{failure.title}: {failure.message}".split())[:300]
                        self.failures[f"{event.label}: {check.name}: {what}"] += 1
        elif isinstance(event, events.NonFatalError):
            self.errors.append(f"{event.label}: {event.info.format()}")
        elif isinstance(event, events.FatalError):
            self.errors.append(f"fatal: {event.exception!r}")
        elif isinstance(event, events.EngineFinished):
            self.failures.update(f"after run: {f.title}" for f in event.failures)


def fuzz(
    app: FastAPI,
    get_token: Callable[[], str],
    *,
    only: list[tuple[str, str]] | None = None,
    skip: list[tuple[str, str]] | None = None,
    parameters: dict[str, str] | None = None,
) -> Run:
    config = SchemathesisConfig.from_dict({
        "seed": SEED,
        "generation": {"max-examples": MAX_EXAMPLES},
        "parameters": parameters or {},
    })  # fmt: skip
    headers = {"Authorization": f"Bearer {get_token()}"}
    schema = schemathesis.openapi.from_asgi(
        "/api/openapi.json", app, config=config, headers=headers
    )
    for method, path in only or []:
        schema = schema.include(method=method, path=path)
    for method, path in skip or []:
        schema = schema.exclude(method=method, path=path)
    schema.auth(bearer(get_token), refresh_interval=None)
    run = Run()
    for event in from_schema(schema).execute():
        run.add(event)
    return run


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_schemathesis_finds_nothing(tmp_path: Path) -> None:
    app = fuzz_app(tmp_path)
    runs: dict[str, Run] = {}
    started = time.monotonic()
    with TestClient(app) as client:
        chief = token(client, ADMIN)
        changer, disabler = token(client, CHANGER), token(client, DISABLER)
        runs["logout (a fresh login each)"] = fuzz(
            app, lambda: token(client, LEAVER), only=[OWN_SESSION[0]]
        )
        runs["password change (changer)"] = fuzz(app, lambda: changer, only=[OWN_SESSION[1]])
        runs["disable (disabler -> target)"] = fuzz(
            app, lambda: disabler, only=[OWN_SESSION[2]], parameters={"path.username": TARGET[0]}
        )
        runs["everything else (chief)"] = fuzz(app, lambda: chief, skip=OWN_SESSION)
        # The supervisor's own session survived it all.
        assert client.get("/api/auth/me", headers={"Authorization": f"Bearer {chief}"}).is_success
    elapsed = time.monotonic() - started
    report = [f"{name}: {run.cases} cases" for name, run in runs.items()]
    print(f"\nschemathesis: {sum(r.cases for r in runs.values())} cases in {elapsed:.0f} s")
    print("\n".join(report))
    problems = [f"{n}x {what}" for run in runs.values() for what, n in run.failures.items()]
    problems += [e for run in runs.values() for e in run.errors]
    assert not problems, "\n".join(problems)
    assert all(run.cases > 0 for run in runs.values()), report

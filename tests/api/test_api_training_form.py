"""The federated run parameters are declared once (FLConfig): the API's request schema
uses its types and bounds, the Training form gets them (and the runner's defaults) from
/api/config, and a request out of bounds never reaches the runner."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import get_type_hints

import pytest
from api_helpers import ADMIN, login, make_settings
from fastapi.testclient import TestClient

from proxima.api import create_app
from proxima.api.schemas import TRAINING_FORM, TrainingStart
from proxima.events import EventBus
from proxima.federated.config import ConfigError, FLConfig
from proxima.federated.runner import FederatedRunner


def test_the_request_schema_has_flconfigs_types_and_bounds() -> None:
    ours = get_type_hints(TrainingStart, include_extras=True)
    theirs = get_type_hints(FLConfig, include_extras=True)
    for name in TRAINING_FORM:
        assert ours[name] == theirs[name] | None, name
        schema = TrainingStart.model_json_schema()["properties"][name]["anyOf"][0]
        assert schema == FLConfig.field_schema(name), name


def test_the_form_gets_the_bounds_and_the_runners_defaults(tmp_path: Path) -> None:
    defaults = FLConfig(rounds=7, batch_size=32, strategy="fedprox")
    runner = FederatedRunner(tmp_path / "runs.db", tmp_path / "models", defaults=defaults)
    app = create_app(make_settings(tmp_path), EventBus(), training=runner)
    with TestClient(app) as client:
        form = client.get("/api/config", headers=login(client, ADMIN)).json()["training_form"]
    assert list(form) == list(TRAINING_FORM)
    assert form["rounds"] == {
        "type": "integer",
        "minimum": 1,
        "maximum": 500,
        "description": "federated rounds",
        "default": 7,
    }
    assert form["learning_rate"]["minimum"] == 1e-6 and form["learning_rate"]["maximum"] == 1
    assert form["batch_size"]["maximum"] == 4096 and form["batch_size"]["default"] == 32
    assert form["fraction_fit"]["exclusiveMinimum"] == 0 and form["fraction_fit"]["maximum"] == 1
    # min_clients: at most the drones of the runner's federation (its default fleet of 3).
    assert (form["local_epochs"]["maximum"], form["min_clients"]["maximum"]) == (100, 3)
    assert form["strategy"]["enum"] == ["fedavg", "fedprox", "fedadam", "fedavgm", "scaffold"]
    assert form["strategy"]["default"] == "fedprox"
    assert form["include_samples"] == {"type": "boolean", "default": True}
    assert {k: v["default"] for k, v in form.items()} == {
        k: v for k, v in asdict(defaults).items() if k in TRAINING_FORM
    }


@pytest.mark.parametrize(
    "field, value",
    [
        ("rounds", 0),
        ("rounds", 501),
        ("local_epochs", 101),
        ("batch_size", 4097),
        ("learning_rate", 0.0),
        ("learning_rate", 5e-324),
        ("learning_rate", 1.5),
        ("fraction_fit", 0.0),
        ("min_clients", 0),
        ("min_clients", 101),
        ("strategy", "fedsgd"),
    ],
)
def test_out_of_bounds_is_refused_by_the_api_and_by_flconfig(
    field: str, value: object, tmp_path: Path
) -> None:
    runner = FederatedRunner(tmp_path / "runs.db", tmp_path / "models")
    app = create_app(make_settings(tmp_path), EventBus(), training=runner)
    with TestClient(app) as client:
        r = client.post("/api/training/runs", json={field: value}, headers=login(client, ADMIN))
    assert r.status_code == 422 and field in r.text
    assert runner.list_runs() == []
    with pytest.raises(ConfigError, match=repr(field.replace("_", "-"))):
        FLConfig(**{field: value})  # the CLI and the Flower apps refuse it too


def test_min_clients_beyond_the_drones_is_refused_by_the_api_and_the_runner(
    tmp_path: Path,
) -> None:
    # The test settings configure two drones: the federation's clients are those two.
    from proxima.api.runtime import federated_drones

    settings = make_settings(tmp_path)
    runner = FederatedRunner(
        tmp_path / "runs.db", tmp_path / "models", drones=federated_drones(settings)
    )
    assert runner.clients == ["main", "second"]
    app = create_app(settings, EventBus(), training=runner)
    with TestClient(app) as client:
        admin = login(client, ADMIN)
        form = client.get("/api/config", headers=admin).json()["training_form"]
        assert form["min_clients"]["maximum"] == 2
        r = client.post("/api/training/runs", json={"min_clients": 3}, headers=admin)
        assert r.status_code == 409
        assert "min_clients 3 is more than the 2 drones" in r.json()["detail"]
        assert "main, second" in r.json()["detail"]
        audit = client.get("/api/audit?action=training.start", headers=admin).json()
        assert audit["entries"][0]["outcome"] == "refused"
    assert runner.list_runs() == []
    with pytest.raises(ValueError, match="'min-clients': 3 is more than the 2 drones"):
        runner.start_run({"min_clients": 3})  # what `proxima fl deploy-local` calls
    assert runner.list_runs() == []

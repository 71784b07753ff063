"""Flower's simulation engine: the `proxima fl simulate` JSON contract, and the visible
"waiting for N drones" state that times out instead of hanging."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fl_helpers import fast_config
from typer.testing import CliRunner

from proxima.cli import app
from proxima.gesture.classifier import GestureClassifier
from proxima.store.training import TrainingStore

pytestmark = pytest.mark.slow


def test_simulate_writes_the_json_contract(tmp_path: Path) -> None:
    out, png = tmp_path / "sim.json", tmp_path / "curve.png"
    models, db = tmp_path / "models", tmp_path / "runs.db"
    result = CliRunner().invoke(app, [
        "fl", "simulate", "--rounds", "2", "--json", str(out), "--png", str(png),
        "--stride", "12", "--set", "test-stride=12", "--local-epochs", "1",
        "--set", "include-samples=false", "--db", str(db), "--models-dir", str(models),
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    assert doc["wall_s"] > 0 and doc["status"] == "completed"
    assert [r["round"] for r in doc["rounds"]] == [0, 1, 2]
    for r in doc["rounds"]:
        assert 0 <= r["global_accuracy"] <= 1
    for r in doc["rounds"][1:]:
        clients = {c["drone"]: c for c in r["clients"]}
        assert set(clients) == {"front", "left", "right"}
        for c in clients.values():
            assert c["status"] == "ok" and c["samples"] > 0 and c["duration_s"] > 0
            assert 0 <= c["accuracy"] <= 1 and c["loss"] > 0
    assert doc["rounds"][-1]["global_accuracy"] > doc["rounds"][0]["global_accuracy"]
    assert png.stat().st_size > 10_000
    # persisted, with a loadable versioned checkpoint and its model card beside it
    run = TrainingStore(db).get_run(doc["run_id"])
    assert run["status"] == "completed" and len(run["rounds"]) == 3
    ckpt = Path(doc["checkpoint"])
    assert ckpt.parent == models / "federated" and ckpt.with_suffix(".md").is_file()
    assert "proxima fl promote" in ckpt.with_suffix(".md").read_text()
    clf = GestureClassifier.load(ckpt)
    assert clf.metadata["federated"]["run_id"] == doc["run_id"]
    curve = CliRunner().invoke(app, ["fl", "curve", doc["run_id"], "--png",
                                     str(tmp_path / "c2.png"), "--db", str(db)])  # fmt: skip
    assert curve.exit_code == 0, curve.output
    assert (tmp_path / "c2.png").stat().st_size > 10_000


def test_too_few_drones_is_a_visible_wait_with_a_timeout(tmp_path: Path) -> None:
    from proxima.federated.simulate import simulate

    statuses: list[tuple[str, str]] = []
    store = TrainingStore(tmp_path / "runs.db")
    cfg = fast_config(min_clients=4, wait_timeout_s=3.0, num_drones=3)
    result = simulate(cfg, store=store, on_status=lambda s, d, _: statuses.append((s, d)))
    waiting = [d for s, d in statuses if s == "waiting"]
    assert waiting and "waiting for 1 more drone(s): 3 of 4 connected" in waiting[0]
    assert result.status == "failed"
    assert "only 3 of 4 drones connected after 3 s" in result.detail
    run = store.run_row(result.run_id)
    assert run["status"] == "failed" and "only 3 of 4" in run["detail"]


def test_keep_round_best_ends_with_the_round_the_drones_validation_scores_best(
    tmp_path: Path,
) -> None:
    from proxima.federated.config import ConfigError
    from proxima.federated.data import test_windows
    from proxima.federated.simulate import simulate
    from proxima.federated.task import Scorer

    with pytest.raises(ConfigError, match=r"keep-round.*fraction-evaluate"):
        fast_config(keep_round="best")
    cfg = fast_config(rounds=3, keep_round="best", fraction_evaluate=1.0,
                      models_dir=str(tmp_path / "models"))  # fmt: skip
    doc = simulate(cfg).to_json()
    assert doc["status"] == "completed"
    rounds = doc["rounds"][1:]
    assert all(r["val_loss"] > 0 and 0 <= r["val_accuracy"] <= 1 for r in rounds)
    best = min(rounds, key=lambda r: r["val_loss"])
    assert doc["kept_round"] == best["round"]
    assert doc["final_accuracy"] == best["global_accuracy"]
    # the saved checkpoint is that round's global model, not the last one's
    clf = GestureClassifier.load(Path(doc["checkpoint"]))
    assert clf.metadata["federated"]["kept_round"] == best["round"]
    weights = {k: v.numpy() for k, v in clf.model.state_dict().items()}
    _, acc = Scorer(cfg, test_windows(cfg))(weights)
    assert acc == pytest.approx(best["global_accuracy"])
    card = Path(doc["checkpoint"]).with_suffix(".md").read_text()
    assert f"Kept: round {best['round']}'s global model (lowest loss" in card

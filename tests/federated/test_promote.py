"""A run's model goes live only by an explicit promotion: `proxima fl promote RUN`
through a running console's API, swapping the live engine's classifier."""

from __future__ import annotations

from pathlib import Path

import pytest
from fl_helpers import fast_config
from typer.testing import CliRunner

from proxima.cli import app
from proxima.federated.checkpoints import save_run_model
from proxima.federated.task import get_weights, new_model
from proxima.store.training import TrainingStore

ADMIN = ("chief", "correct-horse-battery")


@pytest.mark.slow
def test_promote_swaps_the_live_engine_classifier(tmp_path: Path, laser_dir: Path) -> None:
    from proxima.api.runtime import build_runtime
    from proxima.api.server import BackgroundServer
    from proxima.gesture.classifier import default_checkpoint
    from proxima.gesture.ensemble import load_checkpoint
    from proxima.settings import Settings

    models, db = tmp_path / "models", tmp_path / "c.db"
    replay = sorted(laser_dir.glob("DJI_*_hover_f.MP4.csv"))[0]
    window = load_checkpoint(default_checkpoint()).window  # the engine's length
    cfg = fast_config(run_id="20260101-000000-abcd", models_dir=str(models), window=window)
    model, _ = new_model(cfg)
    rounds = [{"round": 0, "global_accuracy": 0.07, "global_loss": 3.1, "clients": []}]
    ckpt, card = save_run_model(cfg, get_weights(model), rounds)
    store = TrainingStore(db)
    store.create_run(cfg.run_id, engine="simulation", params=cfg.to_run_config(), rounds_total=2)
    store.update_run(cfg.run_id, status="completed", checkpoint=str(ckpt), model_card=str(card))
    settings = Settings.load(
        config=None, admin_user=ADMIN[0], admin_password=ADMIN[1],
        streams=[{"name": "front", "uri": f"replay:{replay}@30", "drone": "main"}],
        engine={"checkpoint": str(default_checkpoint())},
        server={"db_path": str(db), "models_dir": str(models)},
    )  # fmt: skip
    runtime = build_runtime(settings, engine=True, drones=False, view=False)
    assert runtime.engine is not None, runtime.notes
    try:
        before = runtime.engine.pipelines["front"].classifier
        assert store.run_row(cfg.run_id)["promoted_at"] is None  # never automatic
        with BackgroundServer(runtime.app) as server:
            args = ["fl", "promote", cfg.run_id, "--url", server.url, "--user", ADMIN[0],
                    "--db", str(db), "--models-dir", str(models)]  # fmt: skip
            bad = CliRunner().invoke(app, [*args, "--password", "wrong-password-1"])
            assert bad.exit_code == 2 and "login" in bad.output
            assert runtime.engine.pipelines["front"].classifier is before
            # a 2-round model is below the one in use: refused unless a reason is given
            guarded = CliRunner().invoke(app, [*args, "--password", ADMIN[1]])
            assert guarded.exit_code == 2 and "override reason" in guarded.output
            assert runtime.engine.pipelines["front"].classifier is before
            ok = CliRunner().invoke(
                app, [*args, "--password", ADMIN[1], "--override-reason", "test run"]
            )
            assert ok.exit_code == 0, ok.output
        after = runtime.engine.pipelines["front"].classifier
        assert after is not before
        assert after.metadata["federated"]["run_id"] == cfg.run_id
        assert store.run_row(cfg.run_id)["promoted_at"] is not None
    finally:
        runtime.close()

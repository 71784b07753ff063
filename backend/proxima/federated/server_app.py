"""The Flower ServerApp: the ground station's side of a run.

Thin: it reads the run config, starts the guarded strategy from the same seeded model
every drone builds (or from the `init` checkpoint), scores the global model on the
held-out set after every round (round 0 is the starting model), records everything, and
saves the final global model with its card. `app` is what `flwr run` loads (see
flower-app/pyproject.toml); `make_server_app` builds one with in-process callbacks for
the simulation engine.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flwr.app import ArrayRecord, ConfigRecord, Context, MetricRecord
from flwr.serverapp import Grid, ServerApp

from proxima.federated.config import ConfigError, FLConfig
from proxima.federated.data import test_windows
from proxima.federated.recorder import RunRecorder, kept_round_row
from proxima.federated.strategy import DronesMissing, GuardedMixin, guarded
from proxima.federated.task import Scorer, start_model

log = logging.getLogger(__name__)


@dataclass
class ServerResult:
    rounds: list[dict[str, Any]]
    checkpoint: Path | None = None
    card: Path | None = None
    error: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    kept_round: int | None = None  # the round whose global model the run ends with

    def final(self) -> dict[str, Any]:
        """The kept round's record (the last round's when none was kept)."""
        return kept_round_row(self.rounds, self.kept_round)


def _weights(arrays: ArrayRecord) -> dict[str, Any]:
    return {k: a.numpy() for k, a in arrays.items()}


def run_server(grid: Grid, cfg: FLConfig, recorder: RunRecorder) -> ServerResult:
    """One whole run on a Grid (simulation or deployment)."""
    import torch

    torch.set_num_threads(cfg.threads)
    try:
        model, _ = start_model(cfg)
    except ConfigError as exc:  # a bad `init` stops the run before any drone trains
        recorder.status("failed", str(exc))
        return ServerResult(rounds=recorder.rounds, error=str(exc))
    initial = ArrayRecord(model.state_dict())
    scorer = Scorer(cfg, test_windows(cfg))
    strategy = guarded(cfg, recorder)
    assert isinstance(strategy, GuardedMixin)  # a Flower strategy with the guard mixed in
    result = ServerResult(rounds=recorder.rounds)
    kept: dict[str, Any] = {"arrays": initial, "round": 0, "val_loss": math.inf}

    def evaluate(server_round: int, arrays: ArrayRecord) -> MetricRecord:
        loss, acc = scorer(_weights(arrays))
        summary = strategy.train_summary.get(server_round, {})
        started = strategy.round_started.get(server_round)
        val = strategy.evaluate_summary.get(server_round, {})
        val_loss = val.get("val_loss")
        recorder.round_done(
            server_round,
            global_accuracy=acc,
            global_loss=loss,
            train_loss=summary.get("train_loss"),
            clients_ok=summary.get("ok", 0),
            clients_failed=summary.get("failed", 0),
            duration_s=time.monotonic() - started if started else 0.0,
            val_loss=val_loss,
            val_accuracy=val.get("val_accuracy"),
        )
        score = math.inf if val_loss is None else val_loss  # a round no drone scored
        if cfg.keep_round == "last" or kept["round"] == 0 or score < kept["val_loss"]:
            kept.update(arrays=arrays, round=server_round, val_loss=score)
        return MetricRecord({"accuracy": acc, "loss": loss})

    recorder.status("running", f"{cfg.strategy}, {cfg.rounds} rounds")
    train_config = ConfigRecord(dict(cfg.to_run_config()))  # drones build the same FLConfig
    try:
        strategy.start(
            grid=grid,
            initial_arrays=initial,
            num_rounds=cfg.rounds,
            timeout=cfg.round_timeout_s,
            train_config=train_config,
            evaluate_config=ConfigRecord(dict(cfg.to_run_config())),
            evaluate_fn=evaluate,
        )
    except DronesMissing as exc:
        result.error = str(exc)
    result.kept_round = kept["round"]
    if len(recorder.rounds) > 1 and cfg.models_dir:
        from proxima.federated.checkpoints import save_run_model

        result.checkpoint, result.card = save_run_model(
            cfg, _weights(kept["arrays"]), recorder.rounds, result.extra, kept=result.kept_round
        )
    return result


def finish(cfg: FLConfig, recorder: RunRecorder, result: ServerResult) -> None:
    """Write the run's outcome (status, checkpoint, final accuracy) to its record."""
    status = "failed" if result.error or len(result.rounds) <= 1 else "completed"
    final = result.final()
    acc = final.get("global_accuracy")
    kept = (
        f" (round {final['round']}'s model, kept by validation)"
        if final and final is not result.rounds[-1]
        else ""
    )
    detail = result.error or (
        f"{len(result.rounds) - 1} rounds, global accuracy "
        + ("n/a" if acc is None else f"{acc:.3f}")
        + kept
    )
    if recorder.store is not None:
        recorder.store.update_run(
            cfg.run_id,
            checkpoint=str(result.checkpoint) if result.checkpoint else None,
            model_card=str(result.card) if result.card else None,
            **({"final_accuracy": acc} if acc is not None else {}),
        )
    recorder.status(status, detail)


def make_server_app(cfg: FLConfig, recorder: RunRecorder, out: list[ServerResult]) -> ServerApp:
    """A ServerApp bound to a config and recorder (the simulation engine's way in)."""
    app = ServerApp()

    @app.main()
    def _main(grid: Grid, context: Context) -> None:
        out.append(run_server(grid, cfg, recorder))

    return app


app = ServerApp()


@app.main()
def main(grid: Grid, context: Context) -> None:
    """Deployment entry point: the run config comes from the FAB plus `flwr run -c`."""
    from proxima.store.training import TrainingStore

    cfg = FLConfig.from_run_config(dict(context.run_config))
    store = TrainingStore(cfg.db) if cfg.db else None
    if store is not None and store.run_row(cfg.run_id) is None:
        store.create_run(
            cfg.run_id, engine="deployment", params=cfg.to_run_config(), rounds_total=cfg.rounds
        )
    if store is not None:
        store.update_run(cfg.run_id, started_at=time.time(), flwr_run_id=str(context.run_id))
    recorder = RunRecorder(cfg.run_id, cfg.rounds, store)
    try:
        result = run_server(grid, cfg, recorder)
    except Exception as exc:
        recorder.status("failed", f"{type(exc).__name__}: {exc}")
        raise
    finish(cfg, recorder, result)
    if store is not None:
        store.update_run(cfg.run_id, finished_at=time.time())

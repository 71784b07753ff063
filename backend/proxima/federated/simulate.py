"""Runs on Flower's simulation engine: one process, drones as virtual SuperNodes.

The engine is Flower's Ray backend. On a small machine its defaults cost more than
training (a 5-round run took 204 s, and Ray's driver peaked at 4.4 GB), so the backend
is sized here: one single-threaded actor per drone (three drones on two cores share
them evenly, where two actors would make every round wait for one actor's second
drone), a small object store, no dashboard, and torch limited to one thread per client.
"""

from __future__ import annotations

import logging
import os
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from proxima.federated.config import FLConfig
from proxima.federated.recorder import RunRecorder, kept_round_row
from proxima.store.training import TrainingStore

log = logging.getLogger(__name__)


def new_run_id() -> str:
    """Sortable by start time (so checkpoint names sort by version), unique by suffix."""
    return datetime.now(UTC).strftime("%Y%m%d-%H%M%S-") + uuid.uuid4().hex[:4]


def backend_config(cfg: FLConfig, cpus: int | None = None) -> dict[str, dict[str, Any]]:
    """Ray with one single-threaded actor per drone (`cpus` caps the actors)."""
    cpus = max(1, min(cpus or cfg.num_drones, cfg.num_drones))
    return {
        "client_resources": {"num_cpus": 1, "num_gpus": 0.0},
        "init_args": {
            "num_cpus": cpus,
            "num_gpus": 0,
            "object_store_memory": 128 * 1024 * 1024,
            "include_dashboard": False,
            "logging_level": "error",
            "log_to_driver": False,
        },
    }


@dataclass
class SimulationResult:
    run_id: str
    rounds: list[dict[str, Any]]
    wall_s: float
    checkpoint: Path | None = None
    card: Path | None = None
    status: str = "completed"
    detail: str = ""
    config: dict[str, Any] = field(default_factory=dict)
    kept_round: int | None = None  # the round whose global model the run ends with

    def to_json(self) -> dict[str, Any]:
        """The `proxima fl simulate --json` contract: `rounds` (each with `round`,
        `global_accuracy` on the temporal test split and per-client metrics) and `wall_s`."""
        return {
            "run_id": self.run_id,
            "engine": "simulation",
            "status": self.status,
            "detail": self.detail,
            "wall_s": round(self.wall_s, 2),
            "rounds": self.rounds,
            "final_accuracy": kept_round_row(self.rounds, self.kept_round).get("global_accuracy"),
            "kept_round": kept_round_row(self.rounds, self.kept_round).get("round"),
            "checkpoint": str(self.checkpoint) if self.checkpoint else None,
            "model_card": str(self.card) if self.card else None,
            "config": self.config,
        }


def simulate(
    cfg: FLConfig,
    *,
    store: TrainingStore | None = None,
    on_round: Callable[[dict[str, Any]], None] | None = None,
    on_status: Callable[[str, str, dict[str, Any]], None] | None = None,
    started_by: str = "",
    cpus: int | None = None,
) -> SimulationResult:
    """One run on the simulation engine with `cfg.num_drones` virtual drones.

    Raises:
        RuntimeError: the engine failed (the run is recorded as failed first).
    """
    from flwr.simulation import run_simulation

    from proxima.federated.client_app import app as client_app
    from proxima.federated.server_app import ServerResult, finish, make_server_app

    cfg.run_id = cfg.run_id or new_run_id()
    if store is not None:
        store.create_run(cfg.run_id, engine="simulation", params=cfg.to_run_config(),
                         rounds_total=cfg.rounds, started_by=started_by)  # fmt: skip
        store.update_run(cfg.run_id, started_at=time.time())
    recorder = RunRecorder(cfg.run_id, cfg.rounds, store, on_round, on_status)
    out: list[ServerResult] = []
    # Ray's workers inherit the environment: one torch / BLAS thread per client.
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, str(cfg.threads))
    t0 = time.perf_counter()
    try:
        run_simulation(
            server_app=make_server_app(cfg, recorder, out),
            client_app=client_app,
            num_supernodes=cfg.num_drones,
            backend_config=backend_config(cfg, cpus),
        )
    except BaseException as exc:
        recorder.status("failed", f"simulation engine: {type(exc).__name__}: {exc}")
        raise RuntimeError(f"simulation failed: {exc}") from exc
    wall = time.perf_counter() - t0
    result = out[0] if out else ServerResult(rounds=recorder.rounds, error="ServerApp did not run")
    finish(cfg, recorder, result)
    if store is not None:
        store.update_run(cfg.run_id, finished_at=time.time())
    return SimulationResult(
        run_id=cfg.run_id,
        rounds=recorder.rounds,
        wall_s=wall,
        checkpoint=result.checkpoint,
        card=result.card,
        status=recorder.last_status,
        detail=result.error,
        config=cfg.to_run_config(),
        kept_round=result.kept_round,
    )
